/// @file
/// `s2kf track --figure F`: one tracked frame drawn from the front and from the side: the recorded
/// markers, the model's markers at the estimated pose, the line between each pair, and the
/// skeleton (joint centres). Data in PREFIX_frameF.csv, script PREFIX_frameF.gp, PNG and SVG.
#pragma once

#include "gnuplot.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/io/atomic_file.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <iomanip>
#include <ostream>
#include <string>

namespace s2kf::cli {

/// Writes the data and draws it. `points`/`visible` are the frame as recorded (recording order).
/// Returns false and says why in `problem` when no figure could be drawn (the data file is kept).
inline bool draw_tracked_frame(const std::string& prefix, long frame, const body::BodyModel& model,
                               const body::MarkerMapping& mapping, const body::Pose& pose,
                               const Eigen::Matrix3Xd& points,
                               const Eigen::Array<bool, Eigen::Dynamic, 1>& visible, std::string& problem) {
  namespace fs = std::filesystem;
  const body::FrameTransforms frames = body::joint_frames(model, pose);
  const Eigen::Matrix3Xd markers = body::marker_positions(model, frames);
  const auto row = [](std::ostream& out, const Eigen::Vector3d& p) {
    out << p.x() << "," << p.y() << "," << p.z() << "\n";
  };
  // Blocks for gnuplot's `index`: 0 recorded markers, 1 model markers, 2 bones, 3 residual lines.
  const fs::path data = prefix + "_frame" + std::to_string(frame) + ".csv";
  io::write_file_atomically(data, [&](std::ostream& out) {
    out << std::setprecision(7)
        << "# x,y,z in mm; blocks: recorded markers, model markers, bones, residuals\n";
    for (int m = 0; m < model.marker_count(); ++m) {
      const int p = mapping.point_of_marker[m];
      if (p >= 0 && p < points.cols() && visible(p) && points.col(p).allFinite()) row(out, points.col(p));
    }
    out << "\n\n";
    for (int m = 0; m < model.marker_count(); ++m)
      if (mapping.point_of_marker[m] >= 0) row(out, markers.col(m));
    out << "\n\n";
    for (int j = 0; j < model.joint_count(); ++j) {
      const Eigen::Vector3d from = frames.origins[model.joints[j].parent_frame], to = frames.origins[j + 1];
      if ((to - from).norm() < 1e-9) continue;  // the 2nd and 3rd DoF of a joint group share a centre
      row(out, from);
      row(out, to);
      out << "\n";
    }
    out << "\n";
    for (int m = 0; m < model.marker_count(); ++m) {
      const int p = mapping.point_of_marker[m];
      if (p < 0 || p >= points.cols() || !visible(p) || !points.col(p).allFinite()) continue;
      row(out, points.col(p));
      row(out, markers.col(m));
      out << "\n";
    }
  });
  if (!have_gnuplot()) {
    problem = "gnuplot is not installed (Debian: apt-get install gnuplot-nox): " + data.string() +
              " holds the figure's data";
    return false;
  }
  const fs::path directory = fs::absolute(data).parent_path();
  const std::string name = data.stem().string(), file = data.filename().string();
  const std::string title = fs::path(prefix).filename().string() + ", frame " + std::to_string(frame);
  const std::string body =
      "  set termoption noenhanced\n  set multiplot layout 1,2 title '" + title +
      ": recorded markers (o), model markers at the estimate (+), skeleton'\n"
      "  set size ratio -1\n  set key below horizontal\n"
      "  do for [v = 1:2] {\n"
      "    h = (v == 1) ? 1 : 2\n"
      "    set xlabel (v == 1) ? 'x (mm)' : 'y (mm)'\n    set ylabel 'z (mm)'\n"
      "    set title (v == 1) ? 'x-z' : 'y-z'\n"
      "    plot '" +
      file +
      "' index 2 using h:3 with lines lw 2 lc rgb '#555555' title 'skeleton', \\\n"
      "         '" +
      file +
      "' index 3 using h:3 with lines lc rgb '#d62728' title 'distance', \\\n"
      "         '" +
      file +
      "' index 0 using h:3 with points pt 6 ps 1.2 lc rgb '#1f77b4' title 'recorded', \\\n"
      "         '" +
      file +
      "' index 1 using h:3 with points pt 1 ps 1.2 lc rgb '#ff7f0e' title 'model'\n"
      "  }\n  unset multiplot";
  return plot(directory, name, body, problem, "1000,700");
}

}  // namespace s2kf::cli
