/// @file
/// The paper's evaluation (section 5) on an in-memory recording, for the S2KF tracker and the
/// per-frame gradient baseline: marker distance, runtime and accuracy against ground truth per
/// method; the occlusion Monte Carlo; the sample-count sweep. A recording is prepared as for
/// tracking (prepare_session); sample sets come from the cache (sample_cache.hpp). The
/// `s2kf evaluate` command and the tests share it.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/sample_cache.hpp>
#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/sim/occlusion.hpp>
#include <s2kf/sim/random.hpp>
#include <s2kf/track/gradient_baseline.hpp>
#include <s2kf/calibration/height_estimate.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracker_options.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/tracking_run.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::evaluation {

/// Throws std::invalid_argument (a sentence) unless `truth` fits the recording: the model's joint
/// columns and one row per frame, numbered 0, 1, ...
void check_truth(const io::MotionTable& truth, const pipeline::Session& setup, Eigen::Index frames);

#if S2KF_DEFINE_HEAVY
S2KF_INLINE void check_truth(const io::MotionTable& truth, const pipeline::Session& setup, Eigen::Index frames) {
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
#endif

/// The first rows of a motion table (all of them when rows <= 0 or beyond its length).
io::MotionTable first_rows(const io::MotionTable& motion, Eigen::Index rows);

#if S2KF_DEFINE_HEAVY
S2KF_INLINE io::MotionTable first_rows(const io::MotionTable& motion, Eigen::Index rows) {
  if (rows <= 0 || rows >= motion.frames()) return motion;
  io::MotionTable head = motion;
  head.values = motion.values.topRows(rows);
  head.frame.resize(static_cast<std::size_t>(rows));
  head.time.resize(static_cast<std::size_t>(rows));
  return head;
}
#endif

/// The mean distance (mm) between the markers a pose predicts (3 x model markers) and the points
/// of `reference` (3 x P) that are mapped and visible there: the paper's "average marker distance",
/// against every recorded marker whether or not the tracker was shown it. NaN when none.
double mean_marker_distance(const Eigen::Matrix3Xd& predicted, const Eigen::Matrix3Xd& reference,
                            const Eigen::Array<bool, Eigen::Dynamic, 1>& reference_visible,
                            const body::MarkerMapping& mapping);

#if S2KF_DEFINE_HEAVY
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
#endif

/// Tracks `input` with one method; `reference` (same frames and points) is what the marker
/// distance is measured against (the input itself, or the complete recording when the input had
/// markers hidden). on_frame(index) is called after every frame.
track::TrackingRun track_recording(const pipeline::Session& setup, const MarkerSequence& input,
                            const MarkerSequence& reference, pipeline::Method method, int samples,
                            std::vector<double>* distance_to_reference = nullptr,
                            const std::function<void(long)>& on_frame = {});

#if S2KF_DEFINE_HEAVY
S2KF_INLINE track::TrackingRun track_recording(const pipeline::Session& setup, const MarkerSequence& input,
                                        const MarkerSequence& reference, pipeline::Method method, int samples,
                                        std::vector<double>* distance_to_reference,
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
    track::Tracker tracker(setup.model, setup.mapping, options, setup.rate_hz, lcd_sample_set(46, samples).set);
    return run_with(tracker);
  }
  track::GradientBaseline baseline(setup.model, setup.mapping);
  return run_with(baseline);
}
#endif

/// One method on one recording, summarised as the paper's evaluation asks (docs/results.md).
struct MethodResult {
  pipeline::Method method = pipeline::Method::s2kf;
  int samples = 0;  ///< S2KF sample count; 0 for the baseline
  track::TrackingRun run;
  long converged_frame = -1;  ///< track::converged_frame(): the running median over 1 s below 1.5 x the median
  double level_mm = 0;        ///< mean marker distance from track::converged_frame on
  double worst_mm = 0;        ///< largest per-frame mean marker distance from track::converged_frame on
  long worst_frame = -1;
  double worst_all_frames_mm = 0;                ///< largest per-frame distance over the whole recording
  double median_ms = 0, p99_ms = 0, max_ms = 0;  ///< latency per frame
  std::optional<TruthComparison> truth;          ///< when ground truth was given
};

MethodResult summarise(pipeline::Method method, int samples, track::TrackingRun run, const pipeline::Session& setup,
                       const io::MotionTable* truth, long warmup);

#if S2KF_DEFINE_HEAVY
S2KF_INLINE MethodResult summarise(pipeline::Method method, int samples, track::TrackingRun run, const pipeline::Session& setup,
                                   const io::MotionTable* truth, long warmup) {
  MethodResult result;
  result.method = method;
  result.samples = method == pipeline::Method::s2kf ? samples : 0;
  result.converged_frame = track::converged_frame(run.mean_marker_distance, track::frames_per_second(setup.rate_hz));
  result.level_mm = result.converged_frame >= 0 ? track::mean_from(run.mean_marker_distance, result.converged_frame)
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
#endif

/// Tracks the recording with one method and summarises it; `truth` (optional) must have a row
/// per frame of the recording with the model's joint columns.
MethodResult evaluate_method(const pipeline::Session& setup, const MarkerSequence& recording, pipeline::Method method,
                             int samples, const io::MotionTable* truth, long warmup,
                             const std::function<void(long)>& on_frame = {});

#if S2KF_DEFINE_HEAVY
S2KF_INLINE MethodResult evaluate_method(const pipeline::Session& setup, const MarkerSequence& recording, pipeline::Method method,
                                         int samples, const io::MotionTable* truth, long warmup,
                                         const std::function<void(long)>& on_frame) {
  track::TrackingRun run = track_recording(setup, recording, recording, method, samples, nullptr, on_frame);
  return summarise(method, samples, std::move(run), setup, truth, warmup);
}
#endif

/// Per-frame minimum, maximum and mean over Monte Carlo runs (NaN values skipped).
struct Band {
  std::vector<double> min, max, mean;
};

Band band_over_runs(const std::vector<std::vector<double>>& runs);

#if S2KF_DEFINE_HEAVY
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
#endif

struct OcclusionOptions {
  int runs = 100;
  std::uint64_t seed = 1;  ///< run r uses the generator seeded with sim::derive_seed(seed, r)
  sim::RandomOcclusion occlusion{sim::kPaperOcclusionProbability, sim::kPaperOcclusionMeanFrames};
  int samples = track::TrackerOptions{}.samples;
  bool baseline = true;  ///< also run the baseline on every occluded recording (it leaves hidden markers out)
};

/// The paper's occlusion experiment: the random process hides markers of a complete recording,
/// each method tracks what is left, and the marker distance is measured against all recorded
/// markers, hidden ones included.
struct OcclusionStudy {
  int runs = 0;
  std::vector<std::vector<int>> hidden;  ///< per run and frame: mapped markers hidden by the process
  std::vector<std::vector<double>> s2kf_distance, baseline_distance;  ///< per run and frame, mm
  Band s2kf, baseline;                                                ///< per frame over runs
  std::vector<double> mean_hidden;                                    ///< per frame, over runs
  double mean_hidden_overall = 0;                                     ///< over runs and frames
  int max_hidden = 0;  ///< most markers hidden in any frame of any run
  int markers = 0;     ///< mapped markers visible in the complete recording (first frame)
  std::vector<double> s2kf_level, baseline_level;   ///< per run: mean distance after its convergence
  double s2kf_worst_mm = 0, baseline_worst_mm = 0;  ///< largest per-frame distance after warm-up, any run
};

/// The recording with the markers a visibility mask hides set to not visible (and NaN).
MarkerSequence hide_points(const MarkerSequence& complete, const sim::Visibility& keep);

#if S2KF_DEFINE_HEAVY
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
#endif

/// `progress(run)` is called after each run. `warmup` frames are left out of the worst distance.
OcclusionStudy occlusion_monte_carlo(const pipeline::Session& setup, const MarkerSequence& complete,
                                     const OcclusionOptions& options, long warmup = 20,
                                     const std::function<void(int)>& progress = {});

#if S2KF_DEFINE_HEAVY
S2KF_INLINE OcclusionStudy occlusion_monte_carlo(const pipeline::Session& setup, const MarkerSequence& complete,
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
    auto track = [&](pipeline::Method method, std::vector<std::vector<double>>& distances, std::vector<double>& levels,
                     double& worst) {
      std::vector<double> distance;
      track_recording(setup, occluded, complete, method, options.samples, &distance);
      levels.push_back(track::level_after_convergence(distance, track::frames_per_second(setup.rate_hz)));
      for (std::size_t k = static_cast<std::size_t>(std::max(0L, warmup)); k < distance.size(); ++k)
        if (std::isfinite(distance[k])) worst = std::max(worst, distance[k]);
      distances.push_back(std::move(distance));
    };
    track(pipeline::Method::s2kf, study.s2kf_distance, study.s2kf_level, study.s2kf_worst_mm);
    if (options.baseline)
      track(pipeline::Method::baseline, study.baseline_distance, study.baseline_level, study.baseline_worst_mm);
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
#endif

/// Latency and accuracy of the S2KF for each sample count L on one recording.
std::vector<MethodResult> sample_sweep(const pipeline::Session& setup, const MarkerSequence& recording,
                                       const std::vector<int>& sample_counts, const io::MotionTable* truth,
                                       long warmup, const std::function<void(int)>& progress = {});

#if S2KF_DEFINE_HEAVY
S2KF_INLINE std::vector<MethodResult> sample_sweep(const pipeline::Session& setup, const MarkerSequence& recording,
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
#endif

}  // namespace s2kf::evaluation
