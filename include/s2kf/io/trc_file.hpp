/// @file
/// Writing recorded marker trajectories as a TRC file (the marker format of OpenSim's Inverse
/// Kinematics and Scale tools), in the same ground frame as the .osim of opensim_model.hpp.
#pragma once

#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/number_text.hpp>
#include <s2kf/io/opensim_model.hpp>

#include <Eigen/Core>

#include <cmath>
#include <iomanip>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::io {

/// The header: "PathFileType 4 (X/Y/Z) NAME", the key line (DataRate, CameraRate, NumFrames, NumMarkers,
/// Units, OrigDataRate, OrigDataStartFrame, OrigNumFrames) and its values (units mm, as recorded), the
/// marker names each followed by two empty cells, the X1 Y1 Z1 X2 ... line and the blank line that
/// precedes the data. Tab-separated.
void write_trc_header(std::ostream& out, const std::string& file_name, double rate_hz, long frames,
                      const std::vector<std::string>& marker_names);

/// One data line: the frame number (TRC counts from 1), the time (s) and each marker's position
/// (`lab_positions_mm`, one column per marker in the header's order, lab frame, mm) turned into
/// OpenSim's ground frame (opensim_ground_from_lab). A marker not seen in this frame (a non-finite
/// coordinate) gets three empty cells, which OpenSim reads as missing.
void write_trc_row(std::ostream& out, long frame_number, double time_s,
                   const Eigen::Ref<const Eigen::Matrix3Xd>& lab_positions_mm);

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

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

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::io
