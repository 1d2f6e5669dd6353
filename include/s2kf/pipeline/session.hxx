/// @file
/// The definitions of <s2kf/pipeline/session.hpp>: inline where the library is used header-only, compiled
/// once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/pipeline/session.hpp>

namespace s2kf::pipeline {
S2KF_INLINE Session prepare_session(FrameSource& source, const body::MarkerSet& set,
                                    const SessionOptions& options, const SampleSet& samples) {
  options.tracker.validate();
  if (source.frame_count() == 0) throw std::invalid_argument("the recording holds no complete frame");
  if (!(source.rate_hz() > 0) || !std::isfinite(source.rate_hz()))
    throw std::invalid_argument("the recording has no valid frame rate");
  Session session;
  session.marker_set = set;
  session.rate_hz = source.rate_hz();
  const body::BodyModel base = body::mmm_body_model(set.reference_height_mm);
  body::BodyModel model = body::apply_marker_set(base, set);
  session.warnings = body::marker_set_warnings(base, model);
  session.mapping = body::map_marker_set(source.labels(), set);
  session.tracker = options.tracker;
  session.tracker.marker_noise_mm_per_marker = marker_noise_of(set);
  const int used = session.mapping.markers_used();
  if (used == 0)
    throw std::invalid_argument(
        "none of its " + std::to_string(source.labels().size()) +
        " point labels is a marker of the marker set " + set.name + " (expected names such as " +
        (set.entries.empty() ? std::string("none") : set.entries.front().label) + ")");
  session.segments = track::observe_segments(model, session.mapping);
  if (session.segments.markers[0] == used)
    throw std::invalid_argument("only the pelvis carries markers of the marker set " + set.name + " (" +
                                std::to_string(used) +
                                " of them): nothing but the pelvis could be tracked; give a marker set that "
                                "names the recording's other labels (--markerset)");
  if (const std::vector<std::string> unobserved = session.segments.unobserved_segments();
      !unobserved.empty()) {
    std::string list;
    for (const std::string& segment : unobserved) list += (list.empty() ? "" : ", ") + segment;
    session.warnings.push_back("not observed: " + list +
                               " (no marker of the set on them or beyond them); their " +
                               std::to_string(session.segments.unobserved_joints.size()) +
                               " joint angles are written as not observed (NaN), not estimated");
  }
  if (used < session.tracker.min_markers_to_start)
    throw std::invalid_argument(
        "only " + std::to_string(used) + " of its labels are markers of the marker set " + set.name +
        "; at least " + std::to_string(session.tracker.min_markers_to_start) + " are needed to track");

  // The rigid marker pairs measure the body in the file's coordinates: they give the height when
  // none is given, and check the units against a given one. Their time is kept apart from the
  // reads'.
  const std::optional<calibration::HeightEstimate> geometric = [&]() {
    track::TimedFrameSource timed(source, session.times.read);
    const double read_before = session.times.read;
    const auto start = std::chrono::steady_clock::now();
    std::optional<calibration::HeightEstimate> estimate =
        calibration::estimate_height(timed, model, session.mapping);
    session.times.height = track::seconds_since(start) - (session.times.read - read_before);
    return estimate;
  }();
  if (options.height_mm > 0) {
    session.height_mm = options.height_mm;
    session.height_source = "given";
  } else if (set.height_mm) {
    session.height_mm = *set.height_mm;
    session.height_source = "from the marker-set file";
  } else if (geometric) {
    session.height_mm = geometric->mm;
    session.height_source = "estimated from " + std::to_string(geometric->pairs) + " rigid marker pairs";
  } else if (options.fallback_height_mm > 0) {
    session.height_mm = options.fallback_height_mm;
    session.height_source = "default (no two markers on one segment to estimate it from)";
    std::ostringstream warning;
    warning << "body height not estimable from the markers; " << options.fallback_height_mm
            << " mm assumed (use --height)";
    session.warnings.push_back(warning.str());
  } else {
    throw std::invalid_argument("the body height cannot be estimated from the markers; give --height");
  }
  if (geometric)
    if (const std::string problem =
            calibration::units_problem(geometric->mm, session.height_mm, session.height_source);
        !problem.empty())
      throw std::invalid_argument(problem);
  if (!plausible_height_mm(session.height_mm))
    throw std::invalid_argument("a body height of " + std::to_string(std::lround(session.height_mm)) +
                                " mm is not a person's; check the file's units or give --height");
  session.model = model.scaled(session.height_mm);

  if (options.calibrate) {
    const SampleSet& calibration_samples =
        options.calibration_samples.count() > 0 ? options.calibration_samples : samples;
    if (calibration_samples.dimension() != samples.dimension())
      throw std::invalid_argument("the calibration's sample set has " +
                                  std::to_string(calibration_samples.dimension()) +
                                  " dimensions but the tracker's " + std::to_string(samples.dimension()));
    calibration::CalibrationOptions calibration = options.calibration;
    calibration.marker_weight = calibration_weights(set, session.tracker.marker_noise_mm);
    session.calibration_stretches =
        calibration_stretches(source.frame_count(), options.calibration_frames, options.calibration_windows);
    try {
      track::TimedFrameSource timed(source, session.times.read);
      MarkerSequence frames;
      if (options.static_trial.frame_count() > 0) {  // first, so its frames are the first static_frames
        frames = static_trial_in_recording_order(options.static_trial, set, session.mapping,
                                                 static_cast<Eigen::Index>(source.labels().size()));
        calibration.static_frames = static_cast<long>(frames.frame_count());
        frames.rate_hz =
            source.rate_hz();  // tracked as the recording's (a still subject: the rate barely matters)
      }
      for (const auto& [first, count] : session.calibration_stretches) {
        if (frames.frame_count() > 0)
          calibration.restart_frames.push_back(static_cast<long>(frames.frame_count()));
        frames.append_frames(read_frames(timed, first, count));
      }
      session.calibration_frames = frames.frame_count();
      session.calibration_sample_count = calibration_samples.count();
      const auto start = std::chrono::steady_clock::now();
      session.calibration = calibration::calibrate_subject(session.model, session.mapping, session.tracker,
                                                           frames, calibration_samples, calibration);
      session.times.calibration = track::seconds_since(start);
      // Never a broken subject: one that no person could be is refused here (calibration_check.hpp).
      const calibration::CalibrationCheck check = calibration::check_calibration(
          session.model, *session.calibration, calibration.static_pose_sd_rad > 0, options.subject_limits);
      if (!check.problem.empty()) throw std::invalid_argument(check.problem);
      session.model = session.calibration->model;
      if (options.noise_from_calibration)
        session.tracker.marker_noise_mm_per_marker = marker_noise_from_residuals(
            session.calibration->marker_residual_rms_mm, session.tracker.marker_noise_mm,
            session.tracker.marker_noise_mm_per_marker);
    } catch (const std::invalid_argument& e) {
      if (!options.calibration_may_fail)
        throw std::invalid_argument(std::string("calibration failed: ") + e.what());
      session.calibration.reset();
      session.calibration_frames = 0;
      session.calibration_sample_count = 0;
      session.calibration_stretches.clear();
      session.warnings.push_back(std::string("subject not calibrated (calibration failed: ") + e.what() +
                                 "); the marker set is used as it is");
    }
  }
  return session;
}
S2KF_INLINE MarkerSequence static_trial_in_recording_order(const MarkerSequence& static_trial,
                                                           const body::MarkerSet& set,
                                                           const body::MarkerMapping& mapping,
                                                           Eigen::Index points) {
  const body::MarkerMapping static_mapping = body::map_marker_set(static_trial.labels, set);
  MarkerSequence frames;
  frames.labels.assign(static_cast<std::size_t>(points), "");
  frames.rate_hz = static_trial.rate_hz;
  frames.resize(static_trial.frame_count());
  int shared = 0;
  for (std::size_t m = 0; m < mapping.point_of_marker.size() && m < static_mapping.point_of_marker.size();
       ++m) {
    const int to = mapping.point_of_marker[m], from = static_mapping.point_of_marker[m];
    if (to < 0 || from < 0 || to >= points) continue;
    ++shared;
    frames.labels[static_cast<std::size_t>(to)] = static_trial.labels[static_cast<std::size_t>(from)];
    frames.positions.middleRows(3 * to, 3) = static_trial.positions.middleRows(3 * from, 3);
    frames.visible.row(to) = static_trial.visible.row(from);
  }
  if (shared < 3)
    throw std::invalid_argument("the static trial shows " + std::to_string(shared) +
                                " of the recording's markers; at least 3 are needed to calibrate with it");
  return frames;
}

S2KF_INLINE track::TrackingRun run_session(const Session& session, FrameSource& source,
                                           const SampleSet& samples, const RunOptions& options,
                                           const RunHooks& hooks) {
  if (options.smooth && options.method != Method::s2kf)
    throw std::invalid_argument("smoothing works on the S2KF's estimates, not the baseline's");
  track::StageTimes times;
  track::TimedFrameSource timed_source(source, times.read);
  std::int64_t next = 0;
  std::string bad_coordinates;
  std::vector<int> point_segment;  // per recording point: the segment its marker rides on, or -1
  track::SegmentObservation observed =
      track::observe_segments(session.model, session.mapping, &point_segment);
  const auto next_frame = [&](MarkerFrame& frame) {
    if (!timed_source.read(next, frame)) return false;
    ++next;
    for (Eigen::Index p = 0; p < frame.positions.cols(); ++p)
      if (frame.visible(p) && frame.positions.col(p).cwiseAbs().maxCoeff() > kAbsurdCoordinateMm) {
        std::ostringstream s;
        s << "frame " << frame.index << ", point " << source.labels()[static_cast<std::size_t>(p)]
          << " is at (" << frame.positions.col(p).transpose()
          << ") mm, beyond a kilometre: the file's units or scale are wrong";
        throw std::invalid_argument(s.str());
      }
    observed.count_frame(frame.visible, point_segment);
    if (hooks.on_read) hooks.on_read(frame);
    return true;
  };
  track::FrameSink timed_sink;
  if (hooks.sink)
    timed_sink = [&](const track::TrackedFrame& frame) {
      const auto start = std::chrono::steady_clock::now();
      hooks.sink(frame);
      times.writing += track::seconds_since(start);
    };
  // The tracking stage is the tracker's own time per frame (hooks and bookkeeping apart).
  const auto with_times = [&](track::TrackingRun run) {
    times.tracking = run.seconds_statistics.sum();  // every frame's, in order
    run.times = times;
    return run;
  };
  // The calibration's distance (calibrated_distance_mm) needs the series over its stretches.
  long series_limit = -1;
  if (options.bounded_memory) {
    series_limit = track::kBoundedSeriesFrames;
    for (const auto& [start, length] : session.calibration_stretches)
      series_limit = std::max(series_limit, static_cast<long>(start + length));
  }
  const std::vector<std::string> joint_names = session.model.joint_names();
  // Joints no marker informs are written as NaN: the filter's value there is the prior's, not a
  // measurement.
  const std::vector<int>& unobserved = session.segments.unobserved_joints;
  const auto blank = [&unobserved](auto&& row) {
    for (int j : unobserved) row(body::kRootValues + j) = std::numeric_limits<double>::quiet_NaN();
  };
  track::FrameSink sink = timed_sink;
  Eigen::VectorXd blanked;
  if (sink && !unobserved.empty())
    sink = [&](const track::TrackedFrame& f) {
      blanked = f.values;
      blank(blanked);
      timed_sink(track::TrackedFrame{f.index, f.frame, f.time, blanked, f.mean_marker_distance,
                                     f.visible_markers, f.estimate});
    };
  const auto blank_table = [&](track::TrackingRun& run) {
    for (Eigen::Index r = 0; r < run.motion.values.rows(); ++r) blank(run.motion.values.row(r));
  };
  if (options.method == Method::baseline) {
    track::GradientBaseline baseline(session.model, session.mapping);
    track::TrackingRun run =
        track::run_tracking(baseline, next_frame, session.rate_hz, joint_names,
                            options.keep_predicted_markers, hooks.on_frame, sink, series_limit);
    blank_table(run);
    run.segments = observed;
    return with_times(std::move(run));
  }
  track::Tracker tracker(session.model, session.mapping, session.tracker, session.rate_hz, samples);
  if (!options.smooth) {
    track::TrackingRun run =
        track::run_tracking(tracker, next_frame, session.rate_hz, joint_names, options.keep_predicted_markers,
                            hooks.on_frame, sink, series_limit);
    blank_table(run);
    run.segments = observed;
    warn_about_rejected_markers(session.model, run);
    return with_times(std::move(run));
  }
  track::TrackingSmoother smoother(tracker);
  const auto on_frame = [&](long index) {
    const auto start = std::chrono::steady_clock::now();
    smoother.record(tracker, index);
    times.smoothing += track::seconds_since(start);
    if (hooks.on_frame) hooks.on_frame(index);
  };
  track::TrackingRun run = track::run_tracking(tracker, next_frame, session.rate_hz, joint_names,
                                               options.keep_predicted_markers, on_frame);
  const auto start = std::chrono::steady_clock::now();
  smoother.smooth(run.motion);
  times.smoothing += track::seconds_since(start);
  blank_table(run);
  run.segments = observed;
  warn_about_rejected_markers(session.model, run);
  if (timed_sink)
    for (Eigen::Index r = 0; r < run.motion.frames(); ++r) {
      const auto f = static_cast<std::size_t>(r);
      const Eigen::VectorXd values = run.motion.values.row(r).transpose();
      timed_sink(track::TrackedFrame{static_cast<long>(r), run.motion.frame[f], run.motion.time[f], values,
                                     run.mean_marker_distance[f], run.visible_markers[f], nullptr});
    }
  return with_times(std::move(run));
}
S2KF_INLINE double calibrated_distance_mm(const Session& session, const track::TrackingRun& run) {
  if (!session.calibration) return std::numeric_limits<double>::quiet_NaN();
  const auto& distance = run.mean_marker_distance;
  std::size_t first = 0;
  while (first < distance.size() && !std::isfinite(distance[first])) ++first;
  const std::size_t from = first + static_cast<std::size_t>(calibration::CalibrationOptions{}.skip_frames);
  double sum = 0;
  long count = 0;
  for (const auto& [start, length] : session.calibration_stretches)
    for (auto f = static_cast<std::size_t>(std::max<std::int64_t>(start, static_cast<std::int64_t>(from)));
         f < distance.size() && f < static_cast<std::size_t>(start + length); ++f)
      if (std::isfinite(distance[f])) sum += distance[f], ++count;
  return count ? sum / static_cast<double>(count) : std::numeric_limits<double>::quiet_NaN();
}

S2KF_INLINE std::vector<double> calibration_weights(const body::MarkerSet& set, double tracker_noise_mm) {
  std::vector<double> weights;
  for (const body::MarkerSetEntry& entry : set.entries) {
    double w = entry.weight;
    if (entry.noise_mm) w *= (tracker_noise_mm * tracker_noise_mm) / (*entry.noise_mm * *entry.noise_mm);
    weights.push_back(w);
  }
  return weights;
}

S2KF_INLINE std::vector<std::pair<std::int64_t, std::int64_t>> calibration_stretches(std::int64_t frames,
                                                                                     std::int64_t budget,
                                                                                     int windows) {
  windows = static_cast<int>(std::min<std::int64_t>(windows, budget / kMinimumStretchFrames));
  if (frames <= budget || windows <= 1) return {{0, std::min(frames, budget)}};
  const std::int64_t length = budget / windows;
  std::vector<std::pair<std::int64_t, std::int64_t>> stretches;
  for (int w = 0; w < windows; ++w) stretches.emplace_back((frames - length) * w / (windows - 1), length);
  return stretches;
}

}  // namespace s2kf::pipeline
