/// @file
/// The definitions of <s2kf/evaluation/evaluation.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/evaluation/evaluation.hpp>

namespace s2kf::evaluation {
S2KF_INLINE void check_truth(const io::MotionTable& truth, const pipeline::Session& setup,
                             Eigen::Index frames) {
  if (truth.joint_names != setup.model.joint_names())
    throw std::invalid_argument("the truth's joint columns are not the body model's " +
                                std::to_string(setup.model.joint_count()) + " joints (BPx ... RAy) in order");
  if (truth.frames() != frames)
    throw std::invalid_argument("the truth has " + std::to_string(truth.frames()) +
                                " frames, the recording " + std::to_string(frames));
  for (Eigen::Index r = 0; r < truth.frames(); ++r)
    if (truth.frame[static_cast<std::size_t>(r)] != r)
      throw std::invalid_argument("the truth's frame numbers must run 0, 1, 2, ...; row " +
                                  std::to_string(r + 1) + " holds frame " +
                                  std::to_string(truth.frame[static_cast<std::size_t>(r)]));
}
S2KF_INLINE io::MotionTable first_rows(const io::MotionTable& motion, Eigen::Index rows) {
  if (rows <= 0 || rows >= motion.frames()) return motion;
  io::MotionTable head = motion;
  head.values = motion.values.topRows(rows);
  head.frame.resize(static_cast<std::size_t>(rows));
  head.time.resize(static_cast<std::size_t>(rows));
  return head;
}
S2KF_INLINE double mean_marker_distance(const Eigen::Matrix3Xd& predicted, const Eigen::Matrix3Xd& reference,
                                        const Eigen::Array<bool, Eigen::Dynamic, 1>& reference_visible,
                                        const body::MarkerMapping& mapping) {
  double sum = 0;
  int count = 0;
  for (std::size_t m = 0; m < mapping.point_of_marker.size(); ++m) {
    const int p = mapping.point_of_marker[m];
    if (p < 0 || p >= reference.cols() || !reference_visible(p) || !reference.col(p).allFinite()) continue;
    sum += (reference.col(p) - predicted.col(static_cast<Eigen::Index>(m))).norm();
    ++count;
  }
  return count ? sum / count : std::numeric_limits<double>::quiet_NaN();
}
S2KF_INLINE track::TrackingRun track_recording(const pipeline::Session& setup, const MarkerSequence& input,
                                               const MarkerSequence& reference, pipeline::Method method,
                                               int samples, std::vector<double>* distance_to_reference,
                                               const std::function<void(long)>& on_frame) {
  if (reference.frame_count() != input.frame_count() || reference.point_count() != input.point_count())
    throw std::invalid_argument("the reference recording must have the input's frames and points");
  Eigen::Index f = 0;
  auto next_frame = [&](MarkerFrame& frame) {
    if (f >= input.frame_count()) return false;
    input.read_frame(f++, frame);
    return true;
  };
  auto run_with = [&](auto& tracker) {
    if (distance_to_reference) distance_to_reference->clear();
    auto each = [&](long index) {
      if (distance_to_reference) {
        const track::FrameEstimate& e = tracker.estimate();
        distance_to_reference->push_back(
            e.tracked ? mean_marker_distance(e.predicted_markers, reference.frame(index),
                                             reference.visible.col(index), setup.mapping)
                      : std::numeric_limits<double>::quiet_NaN());
      }
      if (on_frame) on_frame(index);
    };
    return track::run_tracking(tracker, next_frame, setup.rate_hz, setup.model.joint_names(), false, each);
  };
  if (method == pipeline::Method::s2kf) {
    track::TrackerOptions options = setup.tracker;
    options.samples = samples;
    track::Tracker tracker(setup.model, setup.mapping, options, setup.rate_hz,
                           lcd_sample_set(46, samples).set);
    return run_with(tracker);
  }
  track::GradientBaseline baseline(setup.model, setup.mapping);
  return run_with(baseline);
}
S2KF_INLINE MethodResult summarise(pipeline::Method method, int samples, track::TrackingRun run,
                                   const pipeline::Session& setup, const io::MotionTable* truth,
                                   long warmup) {
  MethodResult result;
  result.method = method;
  result.samples = method == pipeline::Method::s2kf ? samples : 0;
  result.converged_frame =
      track::converged_frame(run.mean_marker_distance, track::frames_per_second(setup.rate_hz));
  result.level_mm = result.converged_frame >= 0
                        ? track::mean_from(run.mean_marker_distance, result.converged_frame)
                        : std::numeric_limits<double>::quiet_NaN();
  const auto& d = run.mean_marker_distance;
  for (std::size_t k = 0; k < d.size(); ++k) {
    if (!std::isfinite(d[k])) continue;
    result.worst_all_frames_mm = std::max(result.worst_all_frames_mm, d[k]);
    if (static_cast<long>(k) >= result.converged_frame && d[k] > result.worst_mm)
      result.worst_mm = d[k], result.worst_frame = static_cast<long>(k);
  }
  std::vector<double> ms;
  for (double s : run.seconds) ms.push_back(1000 * s);
  result.median_ms = track::quantile(ms, 0.5);
  result.p99_ms = track::quantile(ms, 0.99);
  result.max_ms = track::quantile(ms, 1.0);
  if (truth) result.truth = compare_with_truth(setup.model, run.motion, *truth, warmup);
  result.run = std::move(run);
  return result;
}
S2KF_INLINE MethodResult evaluate_method(const pipeline::Session& setup, const MarkerSequence& recording,
                                         pipeline::Method method, int samples, const io::MotionTable* truth,
                                         long warmup, const std::function<void(long)>& on_frame) {
  track::TrackingRun run = track_recording(setup, recording, recording, method, samples, nullptr, on_frame);
  return summarise(method, samples, std::move(run), setup, truth, warmup);
}
S2KF_INLINE Band band_over_runs(const std::vector<std::vector<double>>& runs) {
  Band band;
  const std::size_t frames = runs.empty() ? 0 : runs.front().size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < frames; ++k) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0;
    int count = 0;
    for (const auto& run : runs)
      if (k < run.size() && std::isfinite(run[k]))
        lo = std::min(lo, run[k]), hi = std::max(hi, run[k]), sum += run[k], ++count;
    band.min.push_back(count ? lo : nan);
    band.max.push_back(count ? hi : nan);
    band.mean.push_back(count ? sum / count : nan);
  }
  return band;
}
S2KF_INLINE MarkerSequence hide_points(const MarkerSequence& complete, const sim::Visibility& keep) {
  MarkerSequence occluded = complete;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (Eigen::Index f = 0; f < complete.frame_count(); ++f)
    for (Eigen::Index p = 0; p < complete.point_count(); ++p)
      if (!keep(p, f)) {
        occluded.visible(p, f) = false;
        occluded.positions.block<3, 1>(3 * p, f).setConstant(nan);
      }
  return occluded;
}
S2KF_INLINE OcclusionStudy occlusion_monte_carlo(const pipeline::Session& setup,
                                                 const MarkerSequence& complete,
                                                 const OcclusionOptions& options, long warmup,
                                                 const std::function<void(int)>& progress) {
  if (options.runs < 1) throw std::invalid_argument("the occlusion study needs at least one run");
  sim::validate(options.occlusion);
  OcclusionStudy study;
  study.runs = options.runs;
  for (int p : setup.mapping.point_of_marker)
    if (p >= 0 && complete.frame_count() > 0 && complete.visible(p, 0)) ++study.markers;
  double hidden_sum = 0;
  for (int r = 0; r < options.runs; ++r) {
    std::mt19937_64 rng(sim::derive_seed(options.seed, static_cast<std::uint64_t>(r)));
    sim::Visibility keep = sim::Visibility::Constant(complete.point_count(), complete.frame_count(), true);
    sim::apply_random_occlusion(keep, options.occlusion, rng);
    const MarkerSequence occluded = hide_points(complete, keep);
    std::vector<int> hidden;
    for (Eigen::Index f = 0; f < complete.frame_count(); ++f) {
      int count = 0;
      for (int p : setup.mapping.point_of_marker)
        if (p >= 0 && complete.visible(p, f) && !occluded.visible(p, f)) ++count;
      hidden.push_back(count);
      hidden_sum += count;
      study.max_hidden = std::max(study.max_hidden, count);
    }
    study.hidden.push_back(std::move(hidden));
    auto track = [&](pipeline::Method method, std::vector<std::vector<double>>& distances,
                     std::vector<double>& levels, double& worst) {
      std::vector<double> distance;
      track_recording(setup, occluded, complete, method, options.samples, &distance);
      levels.push_back(track::level_after_convergence(distance, track::frames_per_second(setup.rate_hz)));
      for (std::size_t k = static_cast<std::size_t>(std::max(0L, warmup)); k < distance.size(); ++k)
        if (std::isfinite(distance[k])) worst = std::max(worst, distance[k]);
      distances.push_back(std::move(distance));
    };
    track(pipeline::Method::s2kf, study.s2kf_distance, study.s2kf_level, study.s2kf_worst_mm);
    if (options.baseline)
      track(pipeline::Method::baseline, study.baseline_distance, study.baseline_level,
            study.baseline_worst_mm);
    if (progress) progress(r);
  }
  study.s2kf = band_over_runs(study.s2kf_distance);
  study.baseline = band_over_runs(study.baseline_distance);
  for (Eigen::Index f = 0; f < complete.frame_count(); ++f) {
    double sum = 0;
    for (const auto& run : study.hidden) sum += run[static_cast<std::size_t>(f)];
    study.mean_hidden.push_back(sum / options.runs);
  }
  study.mean_hidden_overall =
      complete.frame_count() ? hidden_sum / (static_cast<double>(options.runs) * complete.frame_count()) : 0;
  return study;
}
S2KF_INLINE std::vector<MethodResult> sample_sweep(const pipeline::Session& setup,
                                                   const MarkerSequence& recording,
                                                   const std::vector<int>& sample_counts,
                                                   const io::MotionTable* truth, long warmup,
                                                   const std::function<void(int)>& progress) {
  std::vector<MethodResult> results;
  for (int samples : sample_counts) {
    results.push_back(evaluate_method(setup, recording, pipeline::Method::s2kf, samples, truth, warmup));
    if (progress) progress(samples);
  }
  return results;
}
}  // namespace s2kf::evaluation
