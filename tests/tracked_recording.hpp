/// @file
/// A recording tracked as `s2kf track` tracks it (height from rigid marker pairs, default options,
/// no calibration), straight through the library: what the tracker tests check, and what the
/// command's tests compare the program with.
#pragma once

#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/calibration/height_estimate.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/tracking_run.hpp>

#include "tracker_samples.hpp"

#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace s2kf::test_support {

/// The frame source run_tracking takes: the recording's frames from the first up to `end`.
inline std::function<bool(MarkerFrame&)> frames_of(const c3d::Recording& recording, Eigen::Index end) {
  auto f = std::make_shared<Eigen::Index>(0);
  return [&recording, end, f](MarkerFrame& frame) {
    if (*f >= end) return false;
    frame.index = *f;
    frame.positions = recording.frame(*f);
    frame.visible = recording.visible.col(*f);
    ++*f;
    return true;
  };
}

inline std::vector<std::string> labels_of(const c3d::Recording& recording) {
  std::vector<std::string> labels;
  for (const auto& label : recording.info.labels) labels.push_back(label.name);
  return labels;
}

struct Tracked {
  body::BodyModel model;  // scaled to the estimated height
  track::TrackingRun run;
  evaluation::TruthComparison truth;
  long converged = 0;
  double level_mm = 0;  // mean marker distance after convergence
  double height_mm = 0;
};

// Tracks `recording` (optionally only its first `frames`) with `model` as it is; the truth is
// compared after `warmup` frames.
inline Tracked track_with_model(const c3d::Recording& recording, const io::MotionTable& truth,
                                const body::BodyModel& model, Eigen::Index frames = 0,
                                track::TrackerOptions options = {}, long warmup = 10) {
  const body::MarkerMapping mapping = body::map_markers(labels_of(recording), model.marker_names());
  Tracked result;
  result.height_mm = model.height_mm;
  result.model = model;
  track::Tracker tracker(model, mapping, options, recording.info.rate, test::tracker_samples(options));
  const Eigen::Index end = frames > 0 ? std::min(frames, recording.frame_count()) : recording.frame_count();
  auto next = frames_of(recording, end);
  result.run = track::run_tracking(tracker, next, recording.info.rate, model.joint_names(), true);
  result.converged =
      track::converged_frame(result.run.mean_marker_distance, track::frames_per_second(recording.info.rate));
  result.level_mm = track::mean_from(result.run.mean_marker_distance, result.converged);
  result.truth = evaluation::compare_with_truth(model, result.run.motion, truth, warmup);
  return result;
}

// Tracks `recording` (optionally only its first `frames`) as `s2kf track` does: height from rigid
// marker pairs, default options.
inline Tracked track_recording(const c3d::Recording& recording, const io::MotionTable& truth,
                               Eigen::Index frames = 0, track::TrackerOptions options = {}) {
  const body::BodyModel model = body::mmm_body_model(1000);
  SequenceFrameSource source(recording);
  const auto height = calibration::estimate_height(
      source, model, body::map_markers(labels_of(recording), model.marker_names()));
  return track_with_model(recording, truth, model.scaled(height ? height->mm : 1750), frames, options);
}

/// The session the evaluation's tests use: the model's own markers, the height given or estimated,
/// no calibration (they compare the methods on the model as it is).
inline pipeline::Session evaluation_session(const MarkerSequence& recording, double height_mm = 0) {
  SequenceFrameSource source(recording);
  pipeline::SessionOptions options;
  options.height_mm = height_mm;
  options.calibrate = false;
  return pipeline::prepare_session(source, body::model_marker_set(body::mmm_body_model(1000)), options,
                                   test::tracker_samples());
}

}  // namespace s2kf::test_support
