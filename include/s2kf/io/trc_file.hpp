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

}  // namespace s2kf::io

#if !defined(S2KF_COMPILED)
#include <s2kf/io/trc_file.hxx>
#endif
