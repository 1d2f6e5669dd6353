/// @file
/// Running a frame tracker (Tracker or GradientBaseline) over a stream of frames and collecting
/// what a user keeps: the motion table, marker distances, visible counts, time per frame, warnings.
/// A caller that writes the motion as it is produced (s2kf track) takes each frame's row from a
/// sink instead, and memory then grows by only the two per-frame series the summary needs.
#pragma once

#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/track/segment_observation.hpp>
#include <s2kf/track/stage_times.hpp>
#include <s2kf/track/tracker.hpp>

#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace s2kf::track {

struct TrackingRun {
  /// NaN rows where not tracked. With a frame sink only joint_names is set (frame, time and
  /// values stay empty: the rows went to the sink).
  io::MotionTable motion;
  std::vector<double> mean_marker_distance;         ///< mm per frame, NaN where nothing was measured
  std::vector<int> visible_markers;                 ///< mapped markers observed per frame; empty with a sink
  std::vector<double> seconds;                      ///< processing time per frame
  std::vector<Eigen::Matrix3Xd> predicted_markers;  ///< only when asked for (evaluation)
  std::vector<std::string> warnings;
  /// Per model marker: frames in which the tracker left the marker out although the recording
  /// showed it, by reason (MarkerRejection: innovation, frozen); empty for the baseline.
  std::vector<long> rejected_by_innovation, rejected_as_frozen;
  StageTimes times;  ///< read, tracking, smoothing and writing (the sink's): filled by pipeline::run_session
  long frames = 0;   ///< frames processed (rows produced), with or without a sink
  long frames_tracked = 0;
  long frames_prediction_only = 0;  ///< tracked frames whose update failed (the prediction was kept)
  /// run_session: per segment, the markers found and the frames in which none was visible.
  SegmentObservation segments;
};

/// One frame as run_tracking produces it, handed to a frame sink before on_frame is called. The
/// references are valid during the call only.
struct TrackedFrame {
  long index = 0;                   ///< 0-based position in the run
  long frame = 0;                   ///< frame number in the recording
  double time = 0;                  ///< seconds: frame / rate
  const Eigen::VectorXd& values;    ///< the motion row: 6 + joints values, NaN where not tracked
  double mean_marker_distance = 0;  ///< mm, NaN where nothing was measured
  int visible_markers = 0;          ///< mapped markers observed
  /// The tracker's whole report; null for rows replayed after smoothing.
  const FrameEstimate* estimate = nullptr;
};

using FrameSink = std::function<void(const TrackedFrame&)>;

/// Adds a frame's left-out markers to the run's counts (the baseline reports none: its rejection
/// list is empty).
inline void count_rejections(const FrameEstimate& e, TrackingRun& run) {
  if (run.rejected_by_innovation.size() != e.rejection.size()) {
    run.rejected_by_innovation.assign(e.rejection.size(), 0);
    run.rejected_as_frozen.assign(e.rejection.size(), 0);
  }
  if (e.rejected_markers == 0) return;
  for (std::size_t m = 0; m < e.rejection.size(); ++m) {
    run.rejected_by_innovation[m] += e.rejection[m] == MarkerRejection::innovation;
    run.rejected_as_frozen[m] += e.rejection[m] == MarkerRejection::frozen;
  }
}

/// Feeds frames from next_frame(frame) -> bool (false at the end) into tracker.process(), frame
/// times from `rate_hz`. `on_frame(index)` is called after each frame (progress, pacing). Updates
/// that fail are reported once per kind with their count and first frame, and tracking goes on.
///
/// Without `sink` the result holds the whole motion table and the visible-marker counts. With a
/// sink, each frame's row goes to sink(frame) as it is produced and is not kept: run.motion holds
/// only the joint names and run.visible_markers stays empty; mean_marker_distance and seconds
/// (16 bytes per frame) are kept either way.
template <typename FrameTracker, typename NextFrame>
TrackingRun run_tracking(FrameTracker& tracker, NextFrame&& next_frame, double rate_hz,
                         const std::vector<std::string>& joint_names, bool keep_predicted_markers = false,
                         const std::function<void(long)>& on_frame = {}, const FrameSink& sink = {}) {
  TrackingRun run;
  run.motion.joint_names = joint_names;
  std::vector<double> table;                              // the rows one after another (without a sink)
  std::map<std::string, std::pair<long, long>> failures;  // status -> (count, first frame)
  MarkerFrame frame;
  const Eigen::Index columns = 6 + static_cast<Eigen::Index>(joint_names.size());
  Eigen::VectorXd row(columns);
  while (next_frame(frame)) {
    const FrameEstimate& e = tracker.process(frame.positions, frame.visible);
    const long index = run.frames++;
    const double time = static_cast<double>(frame.index) / rate_hz;
    if (e.tracked) {
      body::write_pose_row(e.pose, row);
      ++run.frames_tracked;
    } else {
      row.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
    if (sink) {
      sink(TrackedFrame{index, frame.index, time, row, e.mean_marker_distance, e.visible_markers, &e});
    } else {
      run.motion.frame.push_back(frame.index);
      run.motion.time.push_back(time);
      table.insert(table.end(), row.data(), row.data() + columns);
      run.visible_markers.push_back(e.visible_markers);
    }
    run.mean_marker_distance.push_back(e.mean_marker_distance);
    run.seconds.push_back(e.seconds);
    if (keep_predicted_markers) run.predicted_markers.push_back(e.predicted_markers);
    count_rejections(e, run);
    if (e.tracked && e.status != FilterStatus::ok && e.status != FilterStatus::nothing_observed) {
      auto& [count, first] = failures.try_emplace(to_string(e.status), 0L, frame.index).first->second;
      ++count;
      ++run.frames_prediction_only;
      (void)first;
    }
    if (on_frame) on_frame(index);
  }
  if (!sink)
    run.motion.values =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            table.data(), run.frames, columns);
  for (const auto& [status, where] : failures)
    run.warnings.push_back(std::to_string(where.first) + " frame(s) kept the prediction only (" + status +
                           "), first at frame " + std::to_string(where.second));
  return run;
}

}  // namespace s2kf::track
