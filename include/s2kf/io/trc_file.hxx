/// @file
/// The definitions of <s2kf/io/trc_file.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/io/trc_file.hpp>

namespace s2kf::io {

S2KF_INLINE void write_trc_header(std::ostream& out, const std::string& file_name, double rate_hz,
                                  long frames, const std::vector<std::string>& marker_names) {
  if (!(rate_hz > 0)) throw std::invalid_argument("write_trc_header: the frame rate must be positive");
  out << "PathFileType\t4\t(X/Y/Z)\t" << file_name << "\n"
      << "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames"
         "\n"
      << std::setprecision(9) << rate_hz << "\t" << rate_hz << "\t" << frames << "\t" << marker_names.size()
      << "\tmm\t" << rate_hz << "\t1\t" << frames << "\n"
      << "Frame#\tTime";
  for (const std::string& name : marker_names) out << "\t" << name << "\t\t";
  out << "\n\t";
  for (std::size_t m = 1; m <= marker_names.size(); ++m) out << "\tX" << m << "\tY" << m << "\tZ" << m;
  out << "\n\n";
}

S2KF_INLINE void write_trc_row(std::ostream& out, long frame_number, double time_s,
                               const Eigen::Ref<const Eigen::Matrix3Xd>& lab_positions_mm) {
  const Eigen::Matrix3d ground_from_lab = opensim_ground_from_lab();
  out << frame_number << "\t" << std::setprecision(10);
  write_general(out, time_s, 9);
  for (Eigen::Index m = 0; m < lab_positions_mm.cols(); ++m) {
    if (!lab_positions_mm.col(m).allFinite()) {
      out << "\t\t\t";
      continue;
    }
    const Eigen::Vector3d ground = ground_from_lab * lab_positions_mm.col(m);
    for (int k = 0; k < 3; ++k) {
      out << "\t";
      write_general(out, ground(k), 10);
    }
  }
  out << "\n";
}

}  // namespace s2kf::io
