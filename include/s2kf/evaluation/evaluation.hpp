/// @file
/// The paper's evaluation (section 5) on an in-memory recording, for the S2KF tracker and the
/// per-frame gradient baseline: marker distance, runtime and accuracy against ground truth per
/// method; the occlusion Monte Carlo; the sample-count sweep. A recording is prepared as for
/// tracking (prepare_session); sample sets come from the cache (sample_cache.hpp). The
/// `s2kf evaluate` command and the tests share it.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/calibration/height_estimate.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/io/sample_cache.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/sim/occlusion.hpp>
#include <s2kf/sim/random.hpp>
#include <s2kf/track/gradient_baseline.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracker_options.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/tracking_run.hpp>

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

/// The first rows of a motion table (all of them when rows <= 0 or beyond its length).
io::MotionTable first_rows(const io::MotionTable& motion, Eigen::Index rows);

/// The mean distance (mm) between the markers a pose predicts (3 x model markers) and the points
/// of `reference` (3 x P) that are mapped and visible there: the paper's "average marker distance",
/// against every recorded marker whether or not the tracker was shown it. NaN when none.
double mean_marker_distance(const Eigen::Matrix3Xd& predicted, const Eigen::Matrix3Xd& reference,
                            const Eigen::Array<bool, Eigen::Dynamic, 1>& reference_visible,
                            const body::MarkerMapping& mapping);

/// Tracks `input` with one method; `reference` (same frames and points) is what the marker
/// distance is measured against (the input itself, or the complete recording when the input had
/// markers hidden). on_frame(index) is called after every frame.
track::TrackingRun track_recording(const pipeline::Session& setup, const MarkerSequence& input,
                                   const MarkerSequence& reference, pipeline::Method method, int samples,
                                   std::vector<double>* distance_to_reference = nullptr,
                                   const std::function<void(long)>& on_frame = {});

/// One method on one recording, summarised as the paper's evaluation asks (docs/results.md).
struct MethodResult {
  pipeline::Method method = pipeline::Method::s2kf;
  int samples = 0;  ///< S2KF sample count; 0 for the baseline
  track::TrackingRun run;
  long converged_frame =
      -1;               ///< track::converged_frame(): the running median over 1 s below 1.5 x the median
  double level_mm = 0;  ///< mean marker distance from track::converged_frame on
  double worst_mm = 0;  ///< largest per-frame mean marker distance from track::converged_frame on
  long worst_frame = -1;
  double worst_all_frames_mm = 0;                ///< largest per-frame distance over the whole recording
  double median_ms = 0, p99_ms = 0, max_ms = 0;  ///< latency per frame
  std::optional<TruthComparison> truth;          ///< when ground truth was given
};

MethodResult summarise(pipeline::Method method, int samples, track::TrackingRun run,
                       const pipeline::Session& setup, const io::MotionTable* truth, long warmup);

/// Tracks the recording with one method and summarises it; `truth` (optional) must have a row
/// per frame of the recording with the model's joint columns.
MethodResult evaluate_method(const pipeline::Session& setup, const MarkerSequence& recording,
                             pipeline::Method method, int samples, const io::MotionTable* truth, long warmup,
                             const std::function<void(long)>& on_frame = {});

/// Per-frame minimum, maximum and mean over Monte Carlo runs (NaN values skipped).
struct Band {
  std::vector<double> min, max, mean;
};

Band band_over_runs(const std::vector<std::vector<double>>& runs);

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

/// `progress(run)` is called after each run. `warmup` frames are left out of the worst distance.
OcclusionStudy occlusion_monte_carlo(const pipeline::Session& setup, const MarkerSequence& complete,
                                     const OcclusionOptions& options, long warmup = 20,
                                     const std::function<void(int)>& progress = {});

/// Latency and accuracy of the S2KF for each sample count L on one recording.
std::vector<MethodResult> sample_sweep(const pipeline::Session& setup, const MarkerSequence& recording,
                                       const std::vector<int>& sample_counts, const io::MotionTable* truth,
                                       long warmup, const std::function<void(int)>& progress = {});

}  // namespace s2kf::evaluation

#if !defined(S2KF_COMPILED)
#include <s2kf/evaluation/evaluation.hxx>
#endif
