/// @file
/// The definitions of <s2kf/io/mmm_motion.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/io/mmm_motion.hpp>

namespace s2kf::io {

S2KF_INLINE void write_mmm_header(std::ostream& out, const std::string& motion_name, double height_mm) {
  std::string escaped;
  for (const char c : motion_name)
    escaped += c == '"'   ? std::string("&quot;")
               : c == '&' ? std::string("&amp;")
               : c == '<' ? std::string("&lt;")
                          : std::string(1, c);
  out << std::setprecision(9) << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<MMM version=\"2.0\">\n"
      << "  <Motion name=\"" << escaped << "\">\n"
      << "    <Model path=\"mmm.xml\">\n"
      << "      <ModelProcessorConfig type=\"Winter\">\n"
      << "        <Height>" << height_mm / 1000.0 << "</Height>\n"
      << "      </ModelProcessorConfig>\n"
      << "    </Model>\n"
      << "    <Sensors>\n"
      << "      <Sensor type=\"ModelPose\" version=\"1.0\">\n"
      << "        <Configuration />\n"
      << "        <Data>\n";
}

S2KF_INLINE void write_mmm_model_pose(std::ostream& out, double time_s, const MotionRowRef& values) {
  out << std::setprecision(9) << "          <Measurement timestep=\"";
  write_general(out, time_s, 9);
  out << "\">\n            <RootPosition>";
  for (int k = 0; k < 6; ++k) {
    if (k == 3) out << "</RootPosition>\n            <RootRotation>";
    if (k % 3) out << " ";
    write_general(out, values(k), 9);
  }
  out << "</RootRotation>\n          </Measurement>\n";
}

S2KF_INLINE void write_mmm_kinematic_header(std::ostream& out, const std::vector<std::string>& joint_names) {
  out << "        </Data>\n"
      << "      </Sensor>\n"
      << "      <Sensor type=\"Kinematic\" version=\"1.0\">\n"
      << "        <Configuration>\n";
  for (const std::string& joint : joint_names)
    out << "          <Joint name=\"" << mmm_joint_name(joint) << "\" />\n";
  out << "        </Configuration>\n"
      << "        <Data>\n";
}

S2KF_INLINE void write_mmm_joint_position(std::ostream& out, double time_s, const MotionRowRef& values) {
  out << std::setprecision(9) << "          <Measurement timestep=\"";
  write_general(out, time_s, 9);
  out << "\">\n            <JointPosition>";
  for (Eigen::Index c = 6; c < values.size(); ++c) {
    if (c > 6) out << " ";
    write_general(out, angle_or_zero(values(c)), 9);
  }
  out << "</JointPosition>\n"
      << "          </Measurement>\n";
}

S2KF_INLINE void write_mmm_motion(std::ostream& out, const MotionTable& motion,
                                  const std::string& motion_name, double height_mm) {
  motion.check();
  write_mmm_header(out, motion_name, height_mm);
  for (Eigen::Index r = 0; r < motion.frames(); ++r)
    if (is_tracked_row(motion.values.row(r).transpose()))
      write_mmm_model_pose(out, motion.time[static_cast<std::size_t>(r)], motion.values.row(r).transpose());
  write_mmm_kinematic_header(out, motion.joint_names);
  for (Eigen::Index r = 0; r < motion.frames(); ++r)
    if (is_tracked_row(motion.values.row(r).transpose()))
      write_mmm_joint_position(out, motion.time[static_cast<std::size_t>(r)],
                               motion.values.row(r).transpose());
  write_mmm_footer(out);
}

S2KF_INLINE void save_mmm_motion(const std::string& path, const MotionTable& motion,
                                 const std::string& motion_name, double height_mm) {
  write_file_atomically(path,
                        [&](std::ostream& out) { write_mmm_motion(out, motion, motion_name, height_mm); });
}

}  // namespace s2kf::io
