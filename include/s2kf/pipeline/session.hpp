/// @file
/// The tracking pipeline: a session is prepared from a recording and a marker set (the model with
/// the set's markers, the label mapping, the subject's height and where it came from, the subject
/// calibration, the tracker's options), then run from a frame source into a frame sink. `s2kf track`,
/// `s2kf calibrate`, `s2kf evaluate`, the Python module, the benchmarks and the tests all go through
/// these two functions, so they prepare and track a recording the same way.
///
/// No file I/O here: frames come from a FrameSource, rows go to a FrameSink, and the sample set is
/// the caller's (lcd_sample_set from sample_cache.hpp, or any other). Problems with the recording
/// or the options throw std::invalid_argument with one sentence that does not name the file (the
/// caller knows it).
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/marker_set_mapping.hpp>
#include <s2kf/calibration/calibration_check.hpp>
#include <s2kf/calibration/height_estimate.hpp>
#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/track/gradient_baseline.hpp>
#include <s2kf/track/segment_observation.hpp>
#include <s2kf/track/stage_times.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracker_options.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/tracking_run.hpp>
#include <s2kf/track/tracking_smoother.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::pipeline {

/// Below this many millimetres every coordinate is a body's; beyond, the file's units or scale are
/// wrong (a kilometre).
inline constexpr double kAbsurdCoordinateMm = 1e6;

/// A body height no person has: outside (300, 3000) mm.
inline bool plausible_height_mm(double mm) { return mm > 300 && mm < 3000; }

struct SessionOptions {
  track::TrackerOptions tracker;  ///< a preset expanded (track::preset_options), samples included
  double height_mm = 0;           ///< > 0: given; else the marker set's height, else estimated
  /// When no height can be estimated (no two markers on one segment): this height with a warning,
  /// or 0 to refuse the recording.
  double fallback_height_mm = 1750;
  bool calibrate = true;  ///< fit the subject's offsets and bone lengths first
  /// Frames the calibration uses at most: the whole recording when it is no longer, else
  /// `calibration_windows` stretches of calibration_frames / calibration_windows frames spread
  /// evenly from its start to its end, so the subject is fitted on the poses of the whole
  /// recording while the calibration's cost stays bounded whatever the recording's length.
  std::int64_t calibration_frames = 1200;
  int calibration_windows = 4;
  calibration::CalibrationOptions calibration = [] {
    calibration::CalibrationOptions options;
    options.final_pass = false;  // the run's own first frames give the calibrated distance
    return options;
  }();
  /// The sample set of the calibration's tracking pass; empty (no points): the tracker's own. That
  /// pass gives the bundle adjustment its starting poses and decides which residuals it leaves out
  /// as outliers, so a smaller set is faster but can land the calibration elsewhere; the tracker's
  /// set by default, which fits real recordings closest (docs/calibration.md).
  SampleSet calibration_samples;
  /// After calibrating, each marker the set gives no noise of its own gets the tracker's
  /// marker_noise_mm times its calibration residual over the median marker's (clamped to 0.5-2
  /// times; marker_noise_from_residuals): a marker whose soft tissue the constant subject cannot
  /// explain then counts less and pulls the pose less (docs/calibration.md). Without calibration it
  /// does nothing.
  bool noise_from_calibration = true;
  /// A calibration that cannot be done (too few usable frames) leaves the marker set as it is with
  /// a warning (true), or is an error (false: `s2kf calibrate`).
  bool calibration_may_fail = true;
  /// What the calibrated subject may be (calibration::check_calibration).
  calibration::CalibrationLimits subject_limits;
  /// A static trial of the same subject (its frames and labels; calibration.static_pose_sd_rad > 0
  /// and the pose settings in `calibration`): calibrated together with the recording's stretches,
  /// in one bundle adjustment (CalibrationOptions::static_frames). Empty (no frame): none.
  MarkerSequence static_trial;
};

/// What a recording is tracked with, ready to run.
struct Session {
  body::MarkerSet marker_set;
  body::BodyModel model;        ///< the set applied, scaled to the subject, calibrated when asked
  body::MarkerMapping mapping;  ///< recording points -> model markers
  /// Which segments the mapped markers observe; joints of segments no marker informs are written
  /// as NaN by run_session.
  track::SegmentObservation segments;
  track::TrackerOptions tracker;  ///< with the set's per-marker noise
  double rate_hz = 0;
  double height_mm = 0;
  std::string
      height_source;  ///< "given", "from the marker-set file", "estimated from N rigid marker pairs", ...
  std::optional<calibration::SubjectCalibration> calibration;  ///< when calibrated
  std::int64_t calibration_frames = 0;                         ///< frames the calibration used
  Eigen::Index calibration_sample_count = 0;                   ///< samples of the calibration's tracking pass
  /// The stretches of the recording it used: (first frame, frame count).
  std::vector<std::pair<std::int64_t, std::int64_t>> calibration_stretches;
  std::vector<std::string> warnings;  ///< the marker set's and the preparation's
  track::StageTimes times;            ///< read, height and calibration: the preparation's

  int markers_used() const { return mapping.markers_used(); }
};

/// The marker set's per-marker noise as the tracker's option: each marker's `noise_mm`, NaN (the
/// tracker's common noise) where the set gives none; empty when no marker has its own.
inline std::vector<double> marker_noise_of(const body::MarkerSet& set) {
  const bool any = std::any_of(set.entries.begin(), set.entries.end(),
                               [](const body::MarkerSetEntry& entry) { return entry.noise_mm.has_value(); });
  std::vector<double> noise;
  if (!any) return noise;
  for (const body::MarkerSetEntry& entry : set.entries)
    noise.push_back(entry.noise_mm ? *entry.noise_mm : std::numeric_limits<double>::quiet_NaN());
  return noise;
}

/// Per model marker noise SD (mm) from the calibration's residuals (SubjectCalibration::
/// marker_residual_rms_mm): `noise_mm` times the marker's residual RMS over the median of all
/// markers', clamped to [0.5, 2] times, so the common level stays the tracker's. A marker with its
/// own noise in `own` (a finite entry; `own` may be empty) keeps it; one without a residual (never
/// seen in the calibration) gets NaN, the tracker's common noise. Empty when no residual is known.
inline std::vector<double> marker_noise_from_residuals(const std::vector<double>& residual_rms_mm,
                                                       double noise_mm, const std::vector<double>& own) {
  std::vector<double> known;
  for (double r : residual_rms_mm)
    if (std::isfinite(r) && r > 0) known.push_back(r);
  if (known.empty()) return own;
  std::nth_element(known.begin(), known.begin() + static_cast<std::ptrdiff_t>(known.size() / 2), known.end());
  const double median = known[known.size() / 2];
  std::vector<double> noise(residual_rms_mm.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t m = 0; m < noise.size(); ++m) {
    if (m < own.size() && std::isfinite(own[m]))
      noise[m] = own[m];
    else if (std::isfinite(residual_rms_mm[m]) && residual_rms_mm[m] > 0)
      noise[m] = noise_mm * std::clamp(residual_rms_mm[m] / median, 0.5, 2.0);
  }
  return noise;
}

/// The calibration's per-marker weights: the set's weight, times (tracker noise / marker noise)^2
/// where the set gives a marker its own noise.
std::vector<double> calibration_weights(const body::MarkerSet& set, double tracker_noise_mm);

/// The stretches (first frame, count) of a recording of `frames` frames the calibration reads:
/// all of it when it has at most `budget` frames, else `windows` stretches of budget / windows
/// frames, the first at the start, the last at the end, the others evenly between. A stretch is
/// never shorter than kMinimumStretchFrames (the tracker converges at the start of each): a small
/// budget gives fewer stretches, down to one at the start.
inline constexpr std::int64_t kMinimumStretchFrames = 100;
std::vector<std::pair<std::int64_t, std::int64_t>> calibration_stretches(std::int64_t frames,
                                                                         std::int64_t budget, int windows);

/// The static trial's frames with its points in the recording's order (`mapping`: the recording's
/// labels mapped to the model's markers): a model marker the static trial does not show is missing
/// there. Throws std::invalid_argument when it shows fewer than 3 of the recording's markers.
MarkerSequence static_trial_in_recording_order(const MarkerSequence& static_trial, const body::MarkerSet& set,
                                               const body::MarkerMapping& mapping, Eigen::Index points);

/// Prepares a session: checks the recording, maps its labels to the set's markers, finds the
/// subject's height, scales the model and, when asked, calibrates the subject on the first
/// `calibration_frames` frames (samples: the tracker's sample set, for 6 + joints dimensions).
Session prepare_session(FrameSource& source, const body::MarkerSet& set, const SessionOptions& options,
                        const SampleSet& samples);

/// One warning per marker the tracker left out of more than 1 % of the frames, with the reason:
/// a stuck marker or a labelling fault is then named, not averaged into the pose.
inline void warn_about_rejected_markers(const body::BodyModel& model, track::TrackingRun& run) {
  for (std::size_t m = 0; m < run.rejected_by_innovation.size(); ++m) {
    const long innovation = run.rejected_by_innovation[m], frozen = run.rejected_as_frozen[m];
    if (100 * (innovation + frozen) <= run.frames) continue;
    std::string why;
    if (frozen > 0) why = std::to_string(frozen) + " frozen: its coordinates repeat exactly";
    if (innovation > 0)
      why += (why.empty() ? "" : "; ") + std::to_string(innovation) +
             " far from where the body puts it: swapped, mislabelled or jumping";
    // Left out of most frames is no fault of the frames: the subject puts the marker elsewhere.
    if (2 * innovation > run.frames)
      why +=
          "; in most frames, so the subject's placement of it is wrong: a calibration defect, a "
          "marker set that puts it elsewhere, or a label on another marker";
    run.warnings.push_back("marker " + model.markers[m].name + " was left out of " +
                           std::to_string(innovation + frozen) + " of " + std::to_string(run.frames) +
                           " frames (" + why + ")");
  }
}

enum class Method { s2kf, baseline };

inline std::string to_string(Method method) { return method == Method::s2kf ? "s2kf" : "baseline"; }

struct RunOptions {
  Method method = Method::s2kf;
  /// Rauch-Tung-Striebel smoothing after the filter (S2KF only): every frame's posterior is kept
  /// (TrackingSmoother::kBytesPerFrame each) and the rows go to the sink after the backward pass.
  bool smooth = false;
  bool keep_predicted_markers = false;  ///< track::TrackingRun::predicted_markers (evaluation)
  /// A run of unbounded length (a stream): the per-frame series are kept for the first
  /// track::kBoundedSeriesFrames frames (or the calibration's stretches, if longer) and the summary
  /// takes the rest from their statistics, so memory stays flat (with a sink, without smoothing).
  bool bounded_memory = false;
};

/// Hooks of a run, each optional.
struct RunHooks {
  /// Called with every frame as read, before it is tracked: pacing, capturing a frame to draw.
  std::function<void(const MarkerFrame&)> on_read;
  /// Called after every frame with its 0-based index: progress.
  std::function<void(long)> on_frame;
  /// Receives every row; without a sink the run keeps the whole motion table (TrackingRun).
  track::FrameSink sink;
};

/// Runs a prepared session over every frame of `source`. A coordinate beyond a kilometre stops the
/// run with std::invalid_argument (the file's units or scale are wrong). With a sink, memory stays
/// constant in the recording's length (unless smoothing); TrackingRun keeps the per-frame series.
/// TrackingRun::times has the seconds spent reading, tracking, smoothing and in the sink (writing).
track::TrackingRun run_session(const Session& session, FrameSource& source, const SampleSet& samples,
                               const RunOptions& options = {}, const RunHooks& hooks = {});

/// The calibrated subject's mean marker distance over the calibration's stretches, from the run
/// itself: the tracker is causal, so the run's first frames are what a final calibration pass
/// would track (its first skip_frames tracked frames, the convergence, are left out). NaN when the
/// session was not calibrated or nothing was measured there.
double calibrated_distance_mm(const Session& session, const track::TrackingRun& run);

}  // namespace s2kf::pipeline

#if !defined(S2KF_COMPILED)
#include <s2kf/pipeline/session.hxx>
#endif
