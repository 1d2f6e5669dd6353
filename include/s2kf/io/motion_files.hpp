/// @file
/// Writing a tracked or simulated motion (root pose and joint angles per frame) as CSV (the
/// project's own column layout, also used for ground truth) and as an OpenSim motion file (.mot).
#pragma once

#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/number_text.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <istream>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::io {

/// A motion: one row per frame with the root position (mm), root roll/pitch/yaw (rad) and the
/// joint angles (rad, in joint_names order). Frames that were not tracked hold NaN.
struct MotionTable {
  std::vector<std::string> joint_names;
  std::vector<long> frame;   ///< frame numbers as in the recording (0-based)
  std::vector<double> time;  ///< seconds
  Eigen::MatrixXd values;    ///< frames x (6 + joints): root_x,y,z, roll, pitch, yaw, joints...

  Eigen::Index frames() const { return values.rows(); }
  void check() const {
    if (values.cols() != static_cast<Eigen::Index>(6 + joint_names.size()) ||
        frame.size() != static_cast<std::size_t>(values.rows()) || time.size() != frame.size())
      throw std::invalid_argument("MotionTable: frame, time and value rows do not match the joint names");
  }
};

/// The CSV header: frame,time,root_x,root_y,root_z,root_roll,root_pitch,root_yaw,<joints>.
inline std::vector<std::string> motion_columns(const std::vector<std::string>& joint_names) {
  return body::pose_column_names(joint_names);
}

/// One row of a motion: root position, roll/pitch/yaw and joints (a MotionTable row transposed, or
/// any vector of 6 + joints values). Rows of a column-major table bind without a copy.
using MotionRowRef = Eigen::Ref<const Eigen::VectorXd, 0, Eigen::InnerStride<>>;

/// A row is tracked when its root values are finite; the formats below leave out (.mot) or fill in
/// (BVH) the others. Joint angles of a tracked row may still be NaN: joints no marker observes
/// (session.hpp), which the formats without missing values (.mot, BVH, MMM) write as angle_or_zero.
inline bool is_tracked_row(const MotionRowRef& values) {
  return values.head(std::min<Eigen::Index>(body::kRootValues, values.size())).allFinite();
}

/// A joint angle as the formats without missing values write it: 0 where it is not observed.
inline double angle_or_zero(double angle) { return std::isfinite(angle) ? angle : 0.0; }

/// The CSV header line of write_motion_csv.
inline void write_motion_csv_header(std::ostream& out, const std::vector<std::string>& joint_names) {
  const auto columns = motion_columns(joint_names);
  for (std::size_t c = 0; c < columns.size(); ++c) out << (c ? "," : "") << columns[c];
  out << "\n";
}

/// One CSV line of write_motion_csv: frame, time and the values with %.9g, non-finite ones as "nan".
void write_motion_csv_row(std::ostream& out, long frame, double time, const MotionRowRef& values);

/// CSV in mm and rad with full precision (%.9g); untracked values are written as "nan".
void write_motion_csv(std::ostream& out, const MotionTable& motion);

/// The header of write_opensim_mot, up to and including the column names; `rows` is the number of
/// tracked rows that follow.
void write_opensim_mot_header(std::ostream& out, const std::string& name,
                              const std::vector<std::string>& joint_names, std::size_t rows);

/// One line of write_opensim_mot (of a tracked row): time, root translation in metres, angles in
/// degrees, tab-separated, %.9g.
void write_opensim_mot_row(std::ostream& out, double time, const MotionRowRef& values);

/// OpenSim motion file: tab-separated, a header ending in "endheader", angles in degrees
/// (inDegrees=yes), root translation in metres (OpenSim's unit for translational coordinates).
/// Untracked frames are left out, since OpenSim cannot read NaN.
void write_opensim_mot(std::ostream& out, const MotionTable& motion, const std::string& name);

void save_motion_csv(const std::string& path, const MotionTable& motion);

void save_opensim_mot(const std::string& path, const MotionTable& motion, const std::string& name);

/// Reads a motion CSV written by write_motion_csv (or the simulator's truth): the header must be
/// frame,time,root_x,...,root_yaw followed by joint names. Throws std::runtime_error naming the
/// file, line and problem.
MotionTable read_motion_csv(std::istream& in, const std::string& name);

MotionTable load_motion_csv(const std::string& path);

}  // namespace s2kf::io

#if !defined(S2KF_COMPILED)
#include <s2kf/io/motion_files.hxx>
#endif
