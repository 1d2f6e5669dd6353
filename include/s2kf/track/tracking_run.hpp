/// @file
/// Running a frame tracker (Tracker or GradientBaseline) over a stream of frames and collecting
/// what a user keeps: the motion table, marker distances, visible counts, time per frame, warnings.
#pragma once

#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/track/tracker.hpp>

#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace s2kf::track {

struct TrackingRun {
  io::MotionTable motion;                    ///< NaN rows where not tracked
  std::vector<double> mean_marker_distance;  ///< mm per frame, NaN where nothing was measured
  std::vector<int> visible_markers;          ///< mapped markers observed per frame
  std::vector<double> seconds;               ///< processing time per frame
  std::vector<Eigen::Matrix3Xd> predicted_markers;  ///< only when asked for (evaluation)
  std::vector<std::string> warnings;
  long frames_tracked = 0;
};

/// Feeds frames from next_frame(frame) -> bool (false at the end) into tracker.process(), frame
/// times from `rate_hz`. `on_frame(index)` is called after each frame (progress, pacing). Updates
/// that fail are reported once per kind with their count and first frame, and tracking goes on.
template <typename FrameTracker, typename NextFrame>
TrackingRun run_tracking(FrameTracker& tracker, NextFrame&& next_frame, double rate_hz,
                         const std::vector<std::string>& joint_names, bool keep_predicted_markers = false,
                         const std::function<void(long)>& on_frame = {}) {
  TrackingRun run;
  run.motion.joint_names = joint_names;
  std::vector<Eigen::VectorXd> rows;
  std::map<std::string, std::pair<long, long>> failures;  // status -> (count, first frame)
  c3d::Frame frame;
  const Eigen::Index columns = 6 + static_cast<Eigen::Index>(joint_names.size());
  while (next_frame(frame)) {
    const FrameEstimate& e = tracker.process(frame.positions, frame.visible);
    const long index = static_cast<long>(run.motion.frame.size());
    run.motion.frame.push_back(frame.index);
    run.motion.time.push_back(static_cast<double>(frame.index) / rate_hz);
    Eigen::VectorXd row = Eigen::VectorXd::Constant(columns, std::numeric_limits<double>::quiet_NaN());
    if (e.tracked) {
      row.head<3>() = e.pose.root_position;
      row.segment<3>(3) = e.pose.root_rpy;
      row.tail(columns - 6) = e.pose.joints;
      ++run.frames_tracked;
    }
    rows.push_back(row);
    run.mean_marker_distance.push_back(e.mean_marker_distance);
    run.visible_markers.push_back(e.visible_markers);
    run.seconds.push_back(e.seconds);
    if (keep_predicted_markers) run.predicted_markers.push_back(e.predicted_markers);
    if (e.tracked && e.status != FilterStatus::ok && e.status != FilterStatus::nothing_observed) {
      auto& [count, first] = failures.try_emplace(to_string(e.status), 0L, frame.index).first->second;
      ++count;
      (void)first;
    }
    if (on_frame) on_frame(index);
  }
  run.motion.values.resize(static_cast<Eigen::Index>(rows.size()), columns);
  for (std::size_t r = 0; r < rows.size(); ++r) run.motion.values.row(static_cast<Eigen::Index>(r)) = rows[r].transpose();
  for (const auto& [status, where] : failures)
    run.warnings.push_back(std::to_string(where.first) + " frame(s) kept the prediction only (" + status +
                           "), first at frame " + std::to_string(where.second));
  return run;
}

}  // namespace s2kf::track
