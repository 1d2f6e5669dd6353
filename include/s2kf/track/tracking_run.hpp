/// @file
/// Running a frame tracker (Tracker or GradientBaseline) over a stream of frames and collecting
/// what a user keeps: the motion table, marker distances, visible counts, time per frame, warnings.
/// A caller that writes the motion as it is produced (s2kf track) takes each frame's row from a
/// sink instead, and memory then grows by only the two per-frame series the summary needs; a run
/// of unbounded length (s2kf live) keeps them for its first frames only and its memory stays flat.
#pragma once

#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/track/quantile_histogram.hpp>
#include <s2kf/track/segment_observation.hpp>
#include <s2kf/track/stage_times.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracking_metrics.hpp>

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
  /// mm per frame, NaN where nothing was measured; the first series_limit frames only, with one.
  std::vector<double> mean_marker_distance;
  std::vector<int> visible_markers;  ///< mapped markers observed per frame; empty with a sink
  std::vector<double> seconds;       ///< processing time per frame; the first series_limit frames only
  /// -1: the two series above hold every frame; else their first series_limit frames.
  long series_limit = -1;
  /// Every frame's distance (NaN skipped) and processing time in fixed memory: what the summary
  /// reads when the series are cut (complete_series() false).
  QuantileHistogram distance_statistics, seconds_statistics;
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

  /// Whether mean_marker_distance and seconds hold every frame.
  bool complete_series() const { return series_limit < 0 || frames <= series_limit; }
};

/// Frames a run of unbounded length keeps in its per-frame series (16 bytes each, 256 kB): 55 s at
/// 300 Hz, where the filter's convergence is looked for (distance_level).
constexpr long kBoundedSeriesFrames = 1L << 14;

/// The mean marker distance's summary numbers (docs/results.md).
struct DistanceLevel {
  long converged_frame = -1;  ///< converged_frame's rule; -1 when the distance never converged
  double level_mm = std::numeric_limits<double>::quiet_NaN();    ///< mean from converged_frame on
  double overall_mm = std::numeric_limits<double>::quiet_NaN();  ///< mean over every measured frame
};

/// converged_frame and the means of a run. With the series cut, the whole run's median comes from
/// distance_statistics (within its resolution) and the converged frame is looked for where a whole
/// window ahead lies in the kept frames; the means stay exact (sums over every frame).
inline DistanceLevel distance_level(const TrackingRun& run, double rate_hz, double factor = 1.5) {
  DistanceLevel result;
  const std::vector<double>& kept = run.mean_marker_distance;
  const long window = frames_per_second(rate_hz);
  if (run.complete_series()) {
    result.converged_frame = converged_frame(kept, window, factor);
    result.overall_mm = mean_from(kept, 0);
    if (result.converged_frame >= 0) result.level_mm = mean_from(kept, result.converged_frame);
    return result;
  }
  const QuantileHistogram& all = run.distance_statistics;
  result.overall_mm = all.mean();
  const long starts = std::max(0L, static_cast<long>(kept.size()) - window + 1);
  result.converged_frame = converged_frame_below(kept, window, factor * all.quantile(0.5), starts);
  if (result.converged_frame < 0) return result;
  double before = 0;  // the measured frames before the converged one, taken off the whole sum
  long counted = 0;
  for (long f = 0; f < result.converged_frame; ++f)
    if (std::isfinite(kept[static_cast<std::size_t>(f)]))
      before += kept[static_cast<std::size_t>(f)], ++counted;
  result.level_mm = (all.sum() - before) / static_cast<double>(all.count() - counted);
  return result;
}

/// The q-quantile of the tracker's time per frame (s): exact from the series when complete, else
/// from seconds_statistics.
inline double seconds_quantile(const TrackingRun& run, double q) {
  return run.complete_series() ? quantile(run.seconds, q) : run.seconds_statistics.quantile(q);
}

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
/// (16 bytes per frame) are kept either way, for the first `series_limit` frames when it is not -1
/// (their statistics for every frame).
template <typename FrameTracker, typename NextFrame>
TrackingRun run_tracking(FrameTracker& tracker, NextFrame&& next_frame, double rate_hz,
                         const std::vector<std::string>& joint_names, bool keep_predicted_markers = false,
                         const std::function<void(long)>& on_frame = {}, const FrameSink& sink = {},
                         long series_limit = -1) {
  TrackingRun run;
  run.series_limit = series_limit;
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
    if (series_limit < 0 || index < series_limit) {
      run.mean_marker_distance.push_back(e.mean_marker_distance);
      run.seconds.push_back(e.seconds);
    }
    run.distance_statistics.add(e.mean_marker_distance);
    run.seconds_statistics.add(e.seconds);
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
