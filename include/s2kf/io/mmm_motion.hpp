/// @file
/// Writing a motion in the XML motion format of the Master Motor Map framework (MMM, KIT): the
/// root pose as a "ModelPose" sensor and the joint angles as a "Kinematic" sensor, the layout of
/// the KIT Whole-Body Human Motion Database's MMM files.
#pragma once

#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/io/number_text.hpp>

#include <Eigen/Core>

#include <iomanip>
#include <ostream>
#include <string>
#include <vector>

namespace s2kf::io {

/// MMM names a joint's degree of freedom "<name>_joint" (BLNx_joint, LKx_joint, ...).
inline std::string mmm_joint_name(const std::string& joint) { return joint + "_joint"; }

/// Everything before the ModelPose sensor's measurements: the document, the motion, the reference
/// model "mmm.xml" with the Winter model processor at the subject's height (m), and the sensor's
/// opening tags.
void write_mmm_header(std::ostream& out, const std::string& motion_name, double height_mm);

/// One ModelPose measurement: root position (mm) and roll, pitch, yaw (rad, R = Rz Ry Rx).
void write_mmm_model_pose(std::ostream& out, double time_s, const MotionRowRef& values);

/// Closes the ModelPose sensor and opens the Kinematic sensor with its joint list.
void write_mmm_kinematic_header(std::ostream& out, const std::vector<std::string>& joint_names);

/// One Kinematic measurement: the joint angles (rad) in the configuration's order.
void write_mmm_joint_position(std::ostream& out, double time_s, const MotionRowRef& values);

inline void write_mmm_footer(std::ostream& out) {
  out << "        </Data>\n      </Sensor>\n    </Sensors>\n  </Motion>\n</MMM>\n";
}

/// The whole MMM document of a motion; untracked frames are left out (MMM has no missing values).
void write_mmm_motion(std::ostream& out, const MotionTable& motion, const std::string& motion_name,
                      double height_mm);

void save_mmm_motion(const std::string& path, const MotionTable& motion, const std::string& motion_name,
                     double height_mm);

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

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

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::io
