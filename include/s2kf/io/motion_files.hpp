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

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

S2KF_INLINE void write_motion_csv_row(std::ostream& out, long frame, double time,
                                      const MotionRowRef& values) {
  out << std::setprecision(9) << frame << ",";
  write_general(out, time, 9);
  for (Eigen::Index c = 0; c < values.size(); ++c) {
    const double v = values(c);
    out << ",";
    if (std::isfinite(v))
      write_general(out, v, 9);
    else
      out << "nan";
  }
  out << "\n";
}

S2KF_INLINE void write_motion_csv(std::ostream& out, const MotionTable& motion) {
  motion.check();
  write_motion_csv_header(out, motion.joint_names);
  for (Eigen::Index r = 0; r < motion.frames(); ++r)
    write_motion_csv_row(out, motion.frame[static_cast<std::size_t>(r)],
                         motion.time[static_cast<std::size_t>(r)], motion.values.row(r).transpose());
}

S2KF_INLINE void write_opensim_mot_header(std::ostream& out, const std::string& name,
                                          const std::vector<std::string>& joint_names, std::size_t rows) {
  const auto columns = motion_columns(joint_names);
  out << name << "\nversion=1\nnRows=" << rows << "\nnColumns=" << columns.size() - 1
      << "\ninDegrees=yes\nendheader\ntime";
  for (std::size_t c = 2; c < columns.size(); ++c) out << "\t" << columns[c];
  out << "\n";
}

S2KF_INLINE void write_opensim_mot_row(std::ostream& out, double time, const MotionRowRef& values) {
  const double degrees = kDegreesPerRadian;
  out << std::setprecision(9);
  write_general(out, time, 9);
  for (Eigen::Index c = 0; c < values.size(); ++c) {
    out << "\t";
    write_general(out, angle_or_zero(values(c)) * (c < 3 ? 0.001 : degrees), 9);
  }
  out << "\n";
}

S2KF_INLINE void write_opensim_mot(std::ostream& out, const MotionTable& motion, const std::string& name) {
  motion.check();
  std::size_t rows = 0;
  for (Eigen::Index r = 0; r < motion.frames(); ++r) rows += is_tracked_row(motion.values.row(r).transpose());
  write_opensim_mot_header(out, name, motion.joint_names, rows);
  for (Eigen::Index r = 0; r < motion.frames(); ++r)
    if (is_tracked_row(motion.values.row(r).transpose()))
      write_opensim_mot_row(out, motion.time[static_cast<std::size_t>(r)], motion.values.row(r).transpose());
}

S2KF_INLINE void save_motion_csv(const std::string& path, const MotionTable& motion) {
  write_file_atomically(path, [&](std::ostream& out) { write_motion_csv(out, motion); });
}

S2KF_INLINE void save_opensim_mot(const std::string& path, const MotionTable& motion,
                                  const std::string& name) {
  write_file_atomically(path, [&](std::ostream& out) { write_opensim_mot(out, motion, name); });
}

S2KF_INLINE MotionTable read_motion_csv(std::istream& in, const std::string& name) {
  auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream s(line);
    while (std::getline(s, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    return cells;
  };
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(name + ": empty file, expected a motion CSV header");
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const auto header = split(line);
  const std::vector<std::string> fixed = motion_columns({});
  if (header.size() < fixed.size() || !std::equal(fixed.begin(), fixed.end(), header.begin()))
    throw std::runtime_error(name +
                             ": the header does not start with frame,time,root_x,root_y,root_z,root_roll,"
                             "root_pitch,root_yaw");
  MotionTable motion;
  motion.joint_names.assign(header.begin() + static_cast<std::ptrdiff_t>(fixed.size()), header.end());
  std::vector<std::vector<double>> rows;
  for (long number = 2; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const auto cells = split(line);
    if (cells.size() != header.size())
      throw std::runtime_error(name + ": line " + std::to_string(number) + " has " +
                               std::to_string(cells.size()) + " values, the header " +
                               std::to_string(header.size()));
    std::vector<double> row(cells.size());
    for (std::size_t c = 0; c < cells.size(); ++c) {
      char* end = nullptr;
      row[c] = std::strtod(cells[c].c_str(), &end);
      if (end == cells[c].c_str())
        throw std::runtime_error(name + ": line " + std::to_string(number) + ", column " + header[c] + ": '" +
                                 cells[c] + "' is not a number");
    }
    rows.push_back(std::move(row));
  }
  motion.values.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(header.size() - 2));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    motion.frame.push_back(static_cast<long>(rows[r][0]));
    motion.time.push_back(rows[r][1]);
    for (std::size_t c = 2; c < rows[r].size(); ++c)
      motion.values(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c - 2)) = rows[r][c];
  }
  return motion;
}

S2KF_INLINE MotionTable load_motion_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the file");
  return read_motion_csv(in, path);
}

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::io
