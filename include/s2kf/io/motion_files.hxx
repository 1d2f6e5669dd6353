/// @file
/// The definitions of <s2kf/io/motion_files.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/io/motion_files.hpp>

namespace s2kf::io {

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

}  // namespace s2kf::io
