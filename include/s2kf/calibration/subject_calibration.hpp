/// @file
/// Subject calibration: estimating where a subject's markers sit on the segments and how long the
/// subject's bones are, from a recording of that subject. The S2KF tracks the recording once to
/// give every frame a starting pose; a bundle adjustment then solves for all poses and the subject
/// together (Levenberg-Marquardt on the batch least-squares problem, the poses eliminated frame by
/// frame through the Schur complement), with priors that keep offsets near the marker set and bone
/// lengths near the model's.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracker_options.hpp>
#include <s2kf/track/tracking_metrics.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace s2kf::calibration {

struct CalibrationOptions {
  /// Rounds of (track the recording with the current model, then bundle-adjust poses and subject).
  /// One: the bundle adjustment converges from the tracked poses, and a second round did not help.
  int iterations = 1;
  /// Levenberg-Marquardt iterations per bundle adjustment at most; it stops earlier when an
  /// accepted step lowers the cost by less than `relative_tolerance` of it (1e-3: every accuracy
  /// figure within 1 % of 1e-4's, without the crawl of 0.02-0.08 % an iteration to the cap).
  int bundle_iterations = 40;
  double relative_tolerance = 1e-3;
  /// Threads the calibration may use: the stretches of its tracking pass are tracked side by side
  /// (each by a tracker of its own), and the bundle adjustment's per-frame work runs over
  /// kCalibrationChunks fixed chunks of its frames whose sums are added in chunk order, so the
  /// result is the same whatever the number of threads.
  int threads = 1;
  bool estimate_segment_scales = true;  ///< re-estimate bone lengths too (else offsets only)
  /// SD (mm, per coordinate) of a marker's placement around the marker set's offset: a Gaussian
  /// prior in the same units as the marker residuals over the tracker's marker noise. It decides
  /// the directions the data cannot see (an end segment's markers turned about its 3-DoF joint,
  /// which a constant joint-angle offset undoes) and barely moves the ones it sees.
  double offset_prior_sd_mm = 10.0;
  /// SD of a segment's length factor around 1, counted once per frame used (a Gaussian prior in
  /// the same units as the marker residuals over the tracker's marker noise). Over n frames it is
  /// an SD of 0.4 / sqrt(n) (2.3 % at 300 frames): it decides the lengths no marker observes, such
  /// as the upper neck's, and barely touches the well observed ones, whose data grow as fast.
  double scale_prior_sd_per_frame = 0.4;
  /// Directions of the subject unknowns that the data cannot tell from the poses are left to the
  /// prior alone: a direction whose data information (the subject block of the bundle adjustment's
  /// reduced normal matrix, the poses eliminated) is below `prior_only_fraction` of the information
  /// of one marker coordinate seen in every frame used is not moved from the marker set. These are
  /// the gauge directions (all markers of an end segment turned about its joint's axes, which a
  /// constant joint-angle offset undoes; a bone length against the markers beyond it) and the
  /// directions close to them, which soft tissue would otherwise decide. 0 (default): every
  /// direction is estimated, the priors weighing in as usual; a hard cut helped some motions and
  /// hurt others, so weak_direction_shrink, its soft form, is the default instead.
  double prior_only_fraction = 0;
  /// With prior_only_share, prior_only_fraction thresholds instead the share of a direction's
  /// information (the data's with the poses known, plus the prior's) that survives the poses'
  /// elimination: the generalised eigenproblem S v = mu (C + P) v. A gauge keeps none of it; a
  /// direction the poses do not trade with keeps nearly all, however often its markers are hidden.
  /// Off by default: it traded better segments for worse limb flexion and root orientation.
  bool prior_only_share = false;
  /// Shrinkage of the marker offsets towards the marker set in proportion to how weakly the data
  /// see a direction: an extra prior c (x - x0)^T (C + P) (x - x0) on the offsets' deviation x - x0
  /// from the marker set, C the data's information on the offsets with the poses known and P the
  /// prior's (both at the first linearisation). Along the generalised eigenvectors of
  /// S v = mu (C + P) v (S the information with the poses eliminated) it keeps the fraction
  /// mu / (mu + c) of the data's step: a gauge (mu = 0) stays at the marker set, a direction the
  /// poses do not trade with (mu near 1) moves by 1 / (1 + c) of it. The length factors are left
  /// free of it (shrinking them too cost root orientation). 0.03: soft tissue, not the subject,
  /// would otherwise decide the weakly seen directions (docs/calibration.md).
  double weak_direction_shrink = 0.03;
  /// > 0: the recording is a static trial in the model's zero pose (standing upright, every joint
  /// angle 0): each adjusted frame's joint angles get a Gaussian prior at 0 with this SD (rad).
  /// The posture then fixes what no moving recording can tell apart, an end segment's markers
  /// turned about its joint against a constant offset of that joint's angles (the gauges), where
  /// otherwise the marker set's placement decides it. 0: no prior on the poses.
  double static_pose_sd_rad = 0;
  /// > 0 (with static_pose_sd_rad > 0): the static trial's pelvis stands upright too: each of its
  /// adjusted frames gets a Gaussian prior with this SD (rad) on the tilt of the root's vertical
  /// axis from the lab's vertical (the coordinate axis nearest the tracked roots' vertical over the
  /// static frames). Markers placed by their motion (clusters) show the body's tilt against the lab
  /// only through their offsets' priors; the zero pose stands upright. 0: the tilt is free.
  double static_upright_sd_rad = 0;
  /// The static trial's reference pose (joint angles, rad); empty: the zero pose. With more than one
  /// in static_pose_candidates, the one nearest the first tracking pass's mean posture.
  Eigen::VectorXd static_pose;
  /// Reference poses to choose the static trial's from (the posture found from the data); empty:
  /// static_pose.
  std::vector<Eigen::VectorXd> static_pose_candidates;
  /// true: static_pose_sd_rad is the SD of the posture held over the whole trial, not of each
  /// frame's: the prior is counted once over the frames, so their common posture is estimated
  /// near the reference (traded against the offsets' prior) and their sway follows the markers.
  /// false: every frame's angles are held within the SD of the reference.
  bool static_posture_estimated = false;
  /// > 0 (with static_pose_sd_rad > 0): only the recording's first static_frames frames are the
  /// static trial and get the posture's prior; the frames after them are a moving trial of the
  /// same subject, calibrated together with it (one bundle adjustment, the marker offsets and bone
  /// lengths shared). The static frames fix the gauges, the moving ones what bending joints show
  /// (the roll split of upper arm and forearm, the joint axes). 0: every frame is the static trial.
  long static_frames = 0;
  /// > 0 (with static_frames > 0): the static trial's frames count as the distinct postures they
  /// show, a frame being a new one where its markers moved this far (mm, RMS) from the last new one
  /// (detail::weigh_static_frames): a still subject repeats one measurement of the placement, so
  /// counted frame by frame a long static trial would outweigh the moving trial in every direction
  /// both see. 1.5 mm: two frames of a camera system's noise differ by about that much (twice
  /// 0.7 mm per coordinate on simulated ones, each counted), a real still subject's by less.
  /// 0: each frame counts once.
  double static_distinct_mm = 1.5;
  long skip_frames = 20;  ///< frames after the tracker starts that are left out (convergence)
  int stride = 4;         ///< every stride-th tracked frame enters the bundle adjustment
  /// A residual beyond max(outlier_floor_mm, 4 x the round's median residual) is left out
  /// (swapped or ghost markers in real recordings).
  double outlier_floor_mm = 30.0;
  /// Per model marker relative weight (e.g. the marker set's `weight` over its noise squared,
  /// scaled to 1 for the tracker's noise); empty: all 1.
  std::vector<double> marker_weight;
  /// Per model marker: placed by its motion (markerset inference), not named by the marker set;
  /// empty: none. With a static trial (static_pose_sd_rad > 0) such a marker's offset gets the
  /// prior placed_offset_prior_sd_mm and no weak-direction shrinkage: its offset in the set is the
  /// template fit's guess from the same motion, which knows nothing of the gauges (a cluster turned
  /// about its joint) that only the static trial's posture shows, so the static trial decides them.
  std::vector<bool> placed_by_motion;
  /// SD (mm, per coordinate) of a placed marker's offset prior with a static trial: a guard for
  /// directions no frame sees, far looser than the template fit's tens of millimetres of error.
  double placed_offset_prior_sd_mm = 100.0;
  bool final_pass = true;  ///< track once more with the calibrated model to report its distance
  /// Frames of the calibration recording where a new stretch begins (stretches cut from different
  /// parts of a longer recording and put one after another): the tracker starts afresh there, and
  /// skip_frames counts from there.
  std::vector<long> restart_frames;

  void validate() const {
    if (iterations < 1) throw std::invalid_argument("calibration: at least 1 iteration is needed");
    if (bundle_iterations < 1)
      throw std::invalid_argument("calibration: at least 1 bundle-adjustment iteration is needed");
    if (!(offset_prior_sd_mm > 0))
      throw std::invalid_argument("calibration: the offset prior SD must be positive");
    if (!(placed_offset_prior_sd_mm > 0) || !std::isfinite(placed_offset_prior_sd_mm))
      throw std::invalid_argument(
          "calibration: the placed markers' offset prior SD must be positive and finite");
    if (!(scale_prior_sd_per_frame > 0))
      throw std::invalid_argument("calibration: the scale prior SD must be positive");
    if (!(prior_only_fraction >= 0 && prior_only_fraction < 1))
      throw std::invalid_argument("calibration: the prior-only fraction must lie in [0, 1)");
    if (!(weak_direction_shrink >= 0) || !std::isfinite(weak_direction_shrink))
      throw std::invalid_argument("calibration: the weak-direction shrinkage must be finite and >= 0");
    if (!(static_pose_sd_rad >= 0) || !std::isfinite(static_pose_sd_rad))
      throw std::invalid_argument("calibration: the static pose's SD must be finite and >= 0");
    if (!static_pose.allFinite())
      throw std::invalid_argument("calibration: the static pose has a non-finite angle");
    for (const Eigen::VectorXd& pose : static_pose_candidates)
      if (!pose.allFinite()) throw std::invalid_argument("calibration: a static pose has a non-finite angle");
    if (!(static_upright_sd_rad >= 0) || !std::isfinite(static_upright_sd_rad))
      throw std::invalid_argument("calibration: the static trial's upright SD must be finite and >= 0");
    if (static_frames < 0) throw std::invalid_argument("calibration: static_frames must be >= 0");
    if (!(static_distinct_mm >= 0) || !std::isfinite(static_distinct_mm))
      throw std::invalid_argument(
          "calibration: the static trial's distinct-posture distance must be finite and >= 0");
    if (skip_frames < 0 || stride < 1)
      throw std::invalid_argument("calibration: skip_frames >= 0 and stride >= 1");
    if (threads < 1) throw std::invalid_argument("calibration: at least 1 thread is needed");
  }
};

/// The lab's vertical for frames standing upright: the coordinate axis (+-x, +-y or +-z) nearest
/// the mean of their roots' vertical axes (a lab's floor is one of its coordinate planes, and a
/// subject standing still leans far less than 45 deg from it); zero for no frame.
inline Eigen::Vector3d nearest_lab_vertical(const std::vector<Eigen::Matrix3d>& root_rotations) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Matrix3d& rotation : root_rotations) mean += rotation.col(2);
  if (!(mean.norm() > 0)) return Eigen::Vector3d::Zero();
  Eigen::Index axis = 0;
  mean.cwiseAbs().maxCoeff(&axis);
  Eigen::Vector3d vertical = Eigen::Vector3d::Zero();
  vertical(axis) = mean(axis) > 0 ? 1.0 : -1.0;
  return vertical;
}

/// One round: a tracking pass over the recording with the model of that moment, then (except for
/// the final pass) the bundle adjustment that starts from its poses.
struct CalibrationPass {
  double mean_marker_distance_mm = 0;  ///< tracking: mean over the frames from skip_frames after the start on
  long frames_used = 0;                ///< frames that entered the bundle adjustment (0 for the final pass)
  long residuals_rejected = 0;         ///< marker residuals left out as outliers
  int bundle_iterations = 0;           ///< Levenberg-Marquardt iterations taken
  /// RMS marker distance (mm) over the adjusted frames' inlier residuals, before and after the
  /// bundle adjustment.
  double rms_before_mm = 0, rms_after_mm = 0;
  /// The subject directions left to the prior (CalibrationOptions::prior_only_fraction), each with
  /// the ratio of its data information to the prior's and where it lies: the segment (frame name)
  /// whose markers and bone carry most of it, and that share.
  struct PriorOnlyDirection {
    double information_ratio = 0;
    std::string segment;
    double share = 0;
  };
  std::vector<PriorOnlyDirection> prior_only;
  int subject_unknowns = 0;  ///< bone-length factors and marker offsets adjusted (before the above)
};

struct SubjectCalibration {
  body::BodyModel model;                        ///< the calibrated subject (same markers, same order)
  std::map<std::string, double> segment_scale;  ///< bone-length factor per segment, against the input model
  std::vector<CalibrationPass> passes;          ///< pass 0 tracks with the input model
  double mean_marker_distance_before_mm = 0;    ///< pass 0
  /// The final pass; NaN without one (the caller's own tracking with the calibrated model gives it:
  /// the tracker is causal, so its first frames are that pass).
  double mean_marker_distance_after_mm = std::numeric_limits<double>::quiet_NaN();
  /// Per model marker: RMS distance (mm) between the marker and the calibrated model at the
  /// adjusted poses of the last bundle adjustment (its inlier residuals); NaN for a marker the
  /// adjustment did not see.
  std::vector<double> marker_residual_rms_mm;
  /// A static trial's: the reference pose used (index into static_pose_candidates, -1 for
  /// static_pose) and the posture estimated, the adjusted frames' mean joint angles (rad).
  int static_pose_choice = -1;
  Eigen::VectorXd static_posture;
};

/// Calibrates `model` (a base model after apply_marker_set, scaled to the subject's height) on a
/// recording (its frames consecutive, so the tracker can follow them), `mapping` from its points to
/// model markers. Each round tracks the recording with the current model, keeps every stride-th
/// frame's pose, leaves out outlying residuals, and bundle-adjusts those poses together with the
/// bone-length factors and marker offsets. Markers the recording never shows keep their offsets.
/// Joint limits are not touched, and the adjusted poses stay inside them.
SubjectCalibration calibrate_subject(const body::BodyModel& model, const body::MarkerMapping& mapping,
                                     const track::TrackerOptions& tracker_options,
                                     const MarkerSequence& recording, const SampleSet& samples,
                                     const CalibrationOptions& options = {});

/// The calibration's bundle adjustment alone, started at given poses instead of a tracking pass's:
/// adjusts `model` (its bone-length factors and marker offsets, with the priors of `options`)
/// together with the poses on the frames `poses` names, each with every visible mapped marker
/// (no outliers are left out). With the true poses of a simulated recording it shows what the
/// calibration's objective reaches apart from the poses the tracker gives it. With
/// options.static_pose_sd_rad > 0 every frame's joint angles (the first options.static_frames'
/// when that is > 0) get the static trial's prior at options.static_pose (the zero pose when
/// empty), as in calibrate_subject. The result has the adjusted model, its length factors, its
/// per-marker residuals and one pass; frames with fewer than 3 markers are skipped.
SubjectCalibration adjust_subject_at_poses(const body::BodyModel& model, const body::MarkerMapping& mapping,
                                           const track::TrackerOptions& tracker_options,
                                           const MarkerSequence& recording,
                                           const std::vector<std::pair<long, body::Pose>>& poses,
                                           const CalibrationOptions& options = {});

}  // namespace s2kf::calibration

#if !defined(S2KF_COMPILED)
#include <s2kf/calibration/subject_calibration.hxx>
#endif
