/// @file
/// The bundle adjustment behind calibrate_subject (subject_calibration.hpp): marker offsets and
/// segment scales fitted to tracked frames, with the tracking passes that give it its poses.
/// Heavy: included by the definitions (.hxx) that need it, never by a declaration header.
#pragma once

#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/core/bordered_cholesky.hpp>
#include <s2kf/core/parallel_for.hpp>
#include <s2kf/core/product_tiles.hpp>

#include <iterator>

namespace s2kf::calibration {
namespace detail {

/// Segments whose outgoing bones can be scaled: every segment that is the parent of a joint with
/// a non-zero translation.
inline std::vector<std::string> scalable_segments(const body::BodyModel& model) {
  std::vector<std::string> segments;
  for (const body::Joint& joint : model.joints) {
    if (joint.translation.norm() == 0) continue;
    const std::string segment = body::segment_of_frame(model, joint.parent_frame);
    if (std::find(segments.begin(), segments.end(), segment) == segments.end()) segments.push_back(segment);
  }
  return segments;
}

/// The bundle adjustment's frames are split into this many chunks, whatever the thread count.
inline constexpr int kCalibrationChunks = 8;

/// The frames [begin, end) of chunk c of kCalibrationChunks over `size` frames.
inline std::pair<std::size_t, std::size_t> chunk_range(std::size_t size, int c) {
  const auto chunks = static_cast<std::size_t>(kCalibrationChunks);
  return {size * static_cast<std::size_t>(c) / chunks, size * static_cast<std::size_t>(c + 1) / chunks};
}

/// A frame of the bundle adjustment: its pose and the markers (indices into `used`) it fits.
struct BundleFrame {
  long index = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::VectorXd joints;
  std::vector<int> markers;
  /// The joint angles a Gaussian prior pulls this frame's towards (CalibrationOptions::
  /// static_pose_sd_rad); empty: none.
  Eigen::VectorXd prior_joints;
  /// The lab's vertical that a Gaussian prior pulls the root's vertical axis towards
  /// (CalibrationOptions::static_upright_sd_rad); zero: none.
  Eigen::Vector3d prior_up = Eigen::Vector3d::Zero();
  /// How many frames' worth this frame counts (data and priors alike): below 1 for the frames of a
  /// static trial calibrated with a moving one (weigh_static_frames).
  double weight = 1.0;
};

/// The frames counted by their weights.
inline double weighted_frame_count(const std::vector<BundleFrame>& frames) {
  double count = 0;
  for (const BundleFrame& frame : frames) count += frame.weight;
  return count;
}

/// Whether the posture's prior holds `frame` (a frame of the static trial).
inline bool holds_posture_prior(const BundleFrame& frame) { return frame.prior_joints.size() > 0; }

/// Whether the upright prior holds `frame`.
inline bool holds_upright(const BundleFrame& frame) { return frame.prior_up.squaredNorm() > 0; }

/// Gives the frames of the static trial (those the posture's prior holds) the lab's vertical for
/// the upright prior, where options.static_upright_sd_rad asks for it.
inline void hold_static_frames_upright(std::vector<BundleFrame>& frames, const CalibrationOptions& options) {
  if (!(options.static_upright_sd_rad > 0)) return;
  std::vector<Eigen::Matrix3d> rotations;
  for (const BundleFrame& frame : frames)
    if (holds_posture_prior(frame)) rotations.push_back(frame.rotation);
  const Eigen::Vector3d vertical = nearest_lab_vertical(rotations);
  for (BundleFrame& frame : frames)
    if (holds_posture_prior(frame)) frame.prior_up = vertical;
}

/// Whether `frame` belongs to the static trial: every frame, or with options.static_frames > 0
/// the recording's first static_frames.
inline bool in_static_trial(const BundleFrame& frame, const CalibrationOptions& options) {
  return options.static_frames == 0 || frame.index < options.static_frames;
}

/// RMS distance (mm) between the used markers the recording shows in both frames a and b; NaN for
/// fewer than 3 such markers.
inline double marker_rms_between(const body::MarkerMapping& mapping, const MarkerSequence& recording,
                                 const std::vector<int>& used, long a, long b) {
  double sum = 0;
  int count = 0;
  const auto pa = recording.frame(a), pb = recording.frame(b);
  for (int m : used) {
    const int point = mapping.point_of_marker[static_cast<std::size_t>(m)];
    if (point < 0 || point >= pa.cols() || !recording.visible(point, a) || !recording.visible(point, b))
      continue;
    const double d2 = (pa.col(point) - pb.col(point)).squaredNorm();
    if (std::isfinite(d2)) sum += d2, ++count;
  }
  return count >= 3 ? std::sqrt(sum / count) : std::numeric_limits<double>::quiet_NaN();
}

/// With a moving trial beside the static one (options.static_frames > 0), the static trial's frames
/// together count as the postures they show: a frame is a new one where its markers moved
/// options.static_distinct_mm (RMS) or more from the last new one, and each frame weighs the number
/// of new ones over the trial's. A still subject repeats one measurement of the placement (soft
/// tissue included), so its frames carry the information of a few, however many there are.
inline void weigh_static_frames(std::vector<BundleFrame>& frames, const body::MarkerMapping& mapping,
                                const MarkerSequence& recording, const std::vector<int>& used,
                                const CalibrationOptions& options) {
  if (!(options.static_pose_sd_rad > 0) || options.static_frames <= 0 || !(options.static_distinct_mm > 0))
    return;
  long still = 0, distinct = 0, last = -1;
  for (const BundleFrame& frame : frames) {
    if (!in_static_trial(frame, options)) continue;
    ++still;
    const double moved = last < 0 ? std::numeric_limits<double>::quiet_NaN()
                                  : marker_rms_between(mapping, recording, used, last, frame.index);
    if (!(moved < options.static_distinct_mm)) ++distinct, last = frame.index;
  }
  if (distinct >= still) return;
  for (BundleFrame& frame : frames)
    if (in_static_trial(frame, options))
      frame.weight = static_cast<double>(distinct) / static_cast<double>(still);
}

/// The median of `values` with each counted by its weight: the smallest value up to which the
/// weights reach half their sum; with equal weights, track::quantile's median (the mean of the two
/// middle values for an even count). NaN for no value.
inline double weighted_median(const std::vector<double>& values, const std::vector<double>& weights) {
  if (std::all_of(weights.begin(), weights.end(), [&](double w) { return w == weights.front(); }))
    return track::quantile(values, 0.5);
  std::vector<std::size_t> order(values.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  double total = 0;
  for (double w : weights) total += w;
  double below = 0;
  for (std::size_t k : order)
    if ((below += weights[k]) >= total / 2) return values[k];
  return std::numeric_limits<double>::quiet_NaN();
}

/// RMS distance (mm) per model marker between the recording and `model` at the frames' poses,
/// over each frame's listed markers (indices into `used`); NaN for a marker no frame lists.
inline std::vector<double> marker_residual_rms(const body::BodyModel& model,
                                               const body::MarkerMapping& mapping,
                                               const MarkerSequence& recording, const std::vector<int>& used,
                                               const std::vector<BundleFrame>& frames) {
  std::vector<double> sum(static_cast<std::size_t>(model.marker_count()), 0.0);
  std::vector<double> count(sum.size(), 0.0);
  for (const BundleFrame& frame : frames) {
    const Eigen::Matrix3Xd predicted = body::marker_positions(
        model, body::joint_frames(model, frame.position, frame.rotation, frame.joints));
    const auto points = recording.frame(frame.index);
    for (int u : frame.markers) {
      const int m = used[static_cast<std::size_t>(u)];
      const int point = mapping.point_of_marker[static_cast<std::size_t>(m)];
      sum[static_cast<std::size_t>(m)] += frame.weight * (points.col(point) - predicted.col(m)).squaredNorm();
      count[static_cast<std::size_t>(m)] += frame.weight;
    }
  }
  std::vector<double> rms(sum.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t m = 0; m < sum.size(); ++m)
    if (count[m] > 0) rms[m] = std::sqrt(sum[m] / count[m]);
  return rms;
}

/// The bundle adjustment's frames at given poses, each with every used marker (its index into
/// `used`) the recording shows there and, with `static_prior`, the static trial's prior at the zero
/// pose; frames with fewer than 3 such markers are left out. Throws std::invalid_argument for a
/// frame outside the recording or a pose with another joint count than `joint_count`.
inline std::vector<BundleFrame> frames_at_poses(const body::MarkerMapping& mapping,
                                                const MarkerSequence& recording, const std::vector<int>& used,
                                                const std::vector<std::pair<long, body::Pose>>& poses,
                                                Eigen::Index joint_count, bool static_prior,
                                                const Eigen::VectorXd& static_pose = {}) {
  const Eigen::VectorXd reference = static_pose.size() > 0 ? static_pose : Eigen::VectorXd::Zero(joint_count);
  if (static_prior && reference.size() != joint_count)
    throw std::invalid_argument("calibration: the static pose has another joint count than the model");
  std::vector<BundleFrame> frames;
  for (const auto& [index, pose] : poses) {
    if (index < 0 || index >= recording.frame_count())
      throw std::invalid_argument("calibration: a posed frame lies outside the recording");
    if (pose.joints.size() != joint_count)
      throw std::invalid_argument("calibration: a pose has another joint count than the model");
    BundleFrame frame{index, pose.root_position, pose.root_rotation(), pose.joints, {}, {}};
    const auto points = recording.frame(index);
    for (std::size_t u = 0; u < used.size(); ++u) {
      const int point = mapping.point_of_marker[static_cast<std::size_t>(used[u])];
      if (point < points.cols() && recording.visible(point, index) && points.col(point).allFinite())
        frame.markers.push_back(static_cast<int>(u));
    }
    if (frame.markers.size() < 3) continue;
    if (static_prior) frame.prior_joints = reference;
    frames.push_back(std::move(frame));
  }
  return frames;
}

/// The frames' mean joint angles.
inline Eigen::VectorXd mean_joints(const std::vector<BundleFrame>& frames) {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(frames.empty() ? 0 : frames.front().joints.size());
  for (const BundleFrame& frame : frames) sum += frame.joints;
  return frames.empty() ? sum : Eigen::VectorXd(sum / static_cast<double>(frames.size()));
}

/// The frames of the static trial (in_static_trial).
inline std::vector<BundleFrame> static_trial_frames(const std::vector<BundleFrame>& frames,
                                                    const CalibrationOptions& options) {
  std::vector<BundleFrame> kept;
  for (const BundleFrame& frame : frames)
    if (in_static_trial(frame, options)) kept.push_back(frame);
  return kept;
}

/// The static trial's reference pose: options.static_pose (the zero pose when empty), or of the
/// candidates the one nearest (RMS over the joints) the tracked frames' mean posture; `choice` is
/// its index, -1 for static_pose.
inline Eigen::VectorXd choose_static_pose(const CalibrationOptions& options,
                                          const std::vector<BundleFrame>& frames, Eigen::Index joint_count,
                                          int& choice) {
  choice = -1;
  if (options.static_pose_candidates.empty()) {
    if (options.static_pose.size() == 0) return Eigen::VectorXd::Zero(joint_count);
    if (options.static_pose.size() != joint_count)
      throw std::invalid_argument("calibration: the static pose has another joint count than the model");
    return options.static_pose;
  }
  const Eigen::VectorXd posture = mean_joints(frames);
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < options.static_pose_candidates.size(); ++c) {
    const Eigen::VectorXd& candidate = options.static_pose_candidates[c];
    if (candidate.size() != joint_count)
      throw std::invalid_argument("calibration: a static pose has another joint count than the model");
    const double distance = (candidate - posture).squaredNorm();
    if (distance < best) best = distance, choice = static_cast<int>(c);
  }
  return options.static_pose_candidates[static_cast<std::size_t>(choice)];
}

/// Tracks all frames; returns the poses of the frames usable for calibration and the pass's mean
/// marker distance after convergence. The stretches (split at options.restart_frames) are
/// independent, each tracked by a tracker of its own, on up to options.threads threads.
inline std::vector<BundleFrame> track_pass(const body::BodyModel& model, const body::MarkerMapping& mapping,
                                           const track::TrackerOptions& tracker_options,
                                           const MarkerSequence& recording, const SampleSet& samples,
                                           const CalibrationOptions& options, double& mean_distance) {
  std::vector<long> bounds{0};
  for (long f : options.restart_frames)
    if (f > 0 && f < recording.frame_count()) bounds.push_back(f);
  std::sort(bounds.begin(), bounds.end());
  bounds.erase(std::unique(bounds.begin(), bounds.end()), bounds.end());
  bounds.push_back(static_cast<long>(recording.frame_count()));
  struct Stretch {
    std::vector<double> distance;  ///< per frame
    long started = -1;             ///< index into distance of the first tracked frame
    std::vector<BundleFrame> frames;
  };
  std::vector<Stretch> stretches(bounds.size() - 1);
  // The pass's poses start the bundle adjustment and choose its outliers, so they must follow the
  // markers closely: the exact gain and every joint as loose as the flexions (docs/calibration.md).
  track::TrackerOptions pass_options = tracker_options;
  pass_options.information_form_update = false;
  pass_options.joint_speed_per_s = std::max(pass_options.joint_speed_per_s, pass_options.flexion_speed_per_s);
  parallel_for(static_cast<int>(stretches.size()), options.threads, [&](int s) {
    Stretch& stretch = stretches[static_cast<std::size_t>(s)];
    track::Tracker tracker(model, mapping, pass_options, recording.rate_hz, samples);
    MarkerFrame input;
    for (long f = bounds[static_cast<std::size_t>(s)]; f < bounds[static_cast<std::size_t>(s) + 1]; ++f) {
      recording.read_frame(f, input);
      const track::FrameEstimate& estimate = tracker.process(input.positions, input.visible);
      stretch.distance.push_back(estimate.mean_marker_distance);
      if (!estimate.tracked) continue;
      if (stretch.started < 0) stretch.started = static_cast<long>(stretch.distance.size()) - 1;
      const long since = static_cast<long>(stretch.distance.size()) - 1 - stretch.started;
      if (since >= options.skip_frames && since % options.stride == 0 &&
          estimate.status == FilterStatus::ok) {
        BundleFrame frame;
        frame.index = f;
        frame.position = estimate.pose.root_position;
        frame.rotation = estimate.root_rotation;
        frame.joints = estimate.pose.joints;
        stretch.frames.push_back(std::move(frame));
      }
    }
  });
  // The pass's distance: the mean over the frames after the convergence allowance (a late spike
  // must not empty the window, as it can with converged_frame), stretch by stretch.
  double distance_sum = 0;
  long distance_count = 0;
  std::vector<BundleFrame> frames;
  for (Stretch& stretch : stretches) {
    for (std::size_t k =
             static_cast<std::size_t>(stretch.started < 0 ? 0 : stretch.started + options.skip_frames);
         stretch.started >= 0 && k < stretch.distance.size(); ++k)
      if (std::isfinite(stretch.distance[k])) distance_sum += stretch.distance[k], ++distance_count;
    for (BundleFrame& frame : stretch.frames) frames.push_back(std::move(frame));
  }
  mean_distance = distance_count ? distance_sum / static_cast<double>(distance_count)
                                 : std::numeric_limits<double>::quiet_NaN();
  return frames;
}

/// The bundle adjustment's subject unknowns, [length factors (one per scalable segment), offsets
/// (3 per used marker)], and their priors. Length factors multiply the bone translations of the
/// current model (a step s makes them (1 + s) times longer); `cumulative` is their product since
/// the start, which the prior pulls towards 1.
class BundleAdjustment {
 public:
  BundleAdjustment(const body::BodyModel& start, const body::MarkerMapping& mapping,
                   const MarkerSequence& recording, const CalibrationOptions& options, double noise_variance)
      : start_(start),
        mapping_(mapping),
        recording_(recording),
        options_(options),
        noise_variance_(noise_variance) {
    segments_ = options.estimate_segment_scales ? scalable_segments(start) : std::vector<std::string>{};
    cumulative_.assign(segments_.size(), 1.0);
    for (int m = 0; m < start.marker_count(); ++m)
      if (mapping.point_of_marker[static_cast<std::size_t>(m)] >= 0) used_.push_back(m);
    scales_ = static_cast<int>(segments_.size());
    unknowns_ = scales_ + 3 * static_cast<int>(used_.size());
    joint_scale_.assign(static_cast<std::size_t>(start.joint_count()), -1);
    for (int j = 0; j < start.joint_count(); ++j) {
      const std::string segment =
          body::segment_of_frame(start, start.joints[static_cast<std::size_t>(j)].parent_frame);
      const auto found = std::find(segments_.begin(), segments_.end(), segment);
      if (found != segments_.end())
        joint_scale_[static_cast<std::size_t>(j)] = static_cast<int>(found - segments_.begin());
    }
    for (int m : used_) {
      const double w =
          options.marker_weight.empty() ? 1.0 : options.marker_weight[static_cast<std::size_t>(m)];
      weight_.push_back(w / noise_variance);
      // A static trial shows a placed marker's gauges; the template fit's guess must not decide them.
      const bool placed = options.static_pose_sd_rad > 0 && !options.placed_by_motion.empty() &&
                          options.placed_by_motion[static_cast<std::size_t>(m)];
      const double sd = placed ? options.placed_offset_prior_sd_mm : options.offset_prior_sd_mm;
      offset_prior_.push_back(1.0 / (sd * sd));
      placed_.push_back(placed);
    }
  }

  const std::vector<int>& used() const { return used_; }
  const std::vector<std::string>& segments() const { return segments_; }
  const std::vector<double>& cumulative() const { return cumulative_; }
  /// The bone-length factor of each scalable segment since the start, by segment name.
  std::map<std::string, double> segment_scale() const {
    std::map<std::string, double> scale;
    for (std::size_t s = 0; s < segments_.size(); ++s) scale[segments_[s]] = cumulative_[s];
    return scale;
  }

  /// The data-over-prior information ratio below which prior_only_fraction = `fraction` leaves a
  /// direction to the prior, for `frames` frames: that fraction of the ratio of one marker
  /// coordinate seen in every frame, frames x (offset prior SD / marker noise)^2.
  double prior_only_threshold(double fraction, double frames) const {
    return fraction * frames * options_.offset_prior_sd_mm * options_.offset_prior_sd_mm / noise_variance_;
  }

  /// The subject's information from the data of `frames` at their poses and `model` (the
  /// reduced normal matrix without priors or damping, the poses eliminated), in the prior's
  /// metric: the unknowns [length factors, offsets] divided by their prior SDs (`prior_sd`), so
  /// that an eigenvalue is the ratio of the data's information to the prior's along its
  /// eigenvector. What prior_only_fraction thresholds; the identifiable-subject reference uses it
  /// at the true poses.
  Eigen::MatrixXd information_in_prior_metric(const body::BodyModel& model,
                                              const std::vector<BundleFrame>& frames,
                                              Eigen::VectorXd& prior_sd) {
    scale_weight_ = weighted_frame_count(frames) /
                    (options_.scale_prior_sd_per_frame * options_.scale_prior_sd_per_frame);
    pose_prior_frames_ = posture_prior_frames(frames);
    NormalEquations normal;
    linearise_all(model, frames, normal);
    return whitened_information(normal, prior_sd);
  }

  /// Adjusts `model` and the frames' poses in place; fills the pass's iteration count and RMS.
  void adjust(body::BodyModel& model, std::vector<BundleFrame>& frames, CalibrationPass& pass) {
    // The length prior grows with the frames like the data: soft-tissue bias grows with them
    // too, and would otherwise carry the weakly observed lengths (lumbar, trunk) far off.
    scale_weight_ = weighted_frame_count(frames) /
                    (options_.scale_prior_sd_per_frame * options_.scale_prior_sd_per_frame);
    pose_prior_frames_ = posture_prior_frames(frames);
    const double before = cost(model, frames, cumulative_);
    long residuals = 0;
    for (const BundleFrame& frame : frames) residuals += static_cast<long>(frame.markers.size());
    const auto rms = [&](const body::BodyModel& m, const std::vector<BundleFrame>& f) {
      double sum = 0;
      for (const BundleFrame& frame : f) sum += frame_residual_sum(m, frame, false);
      return std::sqrt(sum / static_cast<double>(std::max(residuals, 1L)));
    };
    pass.rms_before_mm = rms(model, frames);
    double current = before, damping = 1e-4;
    NormalEquations normal;
    pass.subject_unknowns = unknowns_;
    for (int it = 0; it < options_.bundle_iterations; ++it) {
      ++pass.bundle_iterations;
      bool accepted = false;
      linearise_all(model, frames, normal);
      if (it == 0) {
        choose_estimated_directions(model, normal, weighted_frame_count(frames), pass);
        if (options_.static_frames > 0) {
          // With a moving trial beside the static one, the shrinkage is measured against the static
          // trial's information alone: the moving frames' would hold the gauges, which only the
          // static trial's posture sees, at the marker set.
          std::vector<BundleFrame> still;
          std::copy_if(frames.begin(), frames.end(), std::back_inserter(still), holds_posture_prior);
          NormalEquations static_normal;
          linearise_all(model, still, static_normal);
          choose_shrinkage(static_normal);
        } else {
          choose_shrinkage(normal);
        }
        current = cost(model, frames, cumulative_);  // with the shrinkage chosen now
      }
      for (int attempt = 0; attempt < 12 && !accepted; ++attempt) {
        body::BodyModel trial_model = model;
        std::vector<BundleFrame> trial_frames = frames;
        std::vector<double> trial_cumulative = cumulative_;
        if (!step(model, normal, damping, trial_model, trial_frames, trial_cumulative)) {
          damping *= 10;
          continue;
        }
        const double trial = cost(trial_model, trial_frames, trial_cumulative);
        if (trial < current) {
          accepted = true;
          const double decrease = current - trial;
          model = std::move(trial_model);
          frames = std::move(trial_frames);
          cumulative_ = std::move(trial_cumulative);
          current = trial;
          // Lowered after every accepted step: keeping it after a refusal spares a quarter of the
          // steps but led HDM05's adjustment to a subject the plausibility check refuses.
          damping = std::max(damping / 10, 1e-9);
          if (decrease <= options_.relative_tolerance * current) it = options_.bundle_iterations;
        } else {
          damping = std::max(damping * 10, 1e-4);
        }
      }
      if (!accepted) break;  // no step lowers the cost: converged as far as the arithmetic allows
    }
    pass.rms_after_mm = rms(model, frames);
  }

 private:
  static constexpr int kRoot = 6;

  /// Sum of weighted squared residuals of one frame's markers (or unweighted, squared mm).
  double frame_residual_sum(const body::BodyModel& model, const BundleFrame& frame, bool weighted) const {
    const body::FrameTransforms tf = body::joint_frames(model, frame.position, frame.rotation, frame.joints);
    const auto y = recording_.frame(frame.index);
    double sum = 0;
    for (int u : frame.markers) {
      const int m = used_[static_cast<std::size_t>(u)];
      const body::Marker& marker = model.markers[static_cast<std::size_t>(m)];
      const Eigen::Vector3d p = tf.origins[static_cast<std::size_t>(marker.frame)] +
                                tf.rotations[static_cast<std::size_t>(marker.frame)] * marker.offset;
      const double r2 = (y.col(mapping_.point_of_marker[static_cast<std::size_t>(m)]) - p).squaredNorm();
      sum += weighted ? weight_[static_cast<std::size_t>(u)] * r2 : r2;
    }
    return sum;
  }

  /// The objective: weighted data residuals plus both priors.
  double cost(const body::BodyModel& model, const std::vector<BundleFrame>& frames,
              const std::vector<double>& cumulative) const {
    std::vector<double> chunk_sum(kCalibrationChunks, 0.0);
    parallel_for(kCalibrationChunks, options_.threads, [&](int c) {
      const auto [begin, end] = chunk_range(frames.size(), c);
      for (std::size_t k = begin; k < end; ++k) {
        const BundleFrame& frame = frames[k];
        double& sum = chunk_sum[static_cast<std::size_t>(c)];
        sum += frame.weight * frame_residual_sum(model, frame, true);
        if (holds_posture_prior(frame))
          sum += frame.weight * pose_prior_weight() * (frame.joints - frame.prior_joints).squaredNorm();
        if (holds_upright(frame))
          sum +=
              frame.weight * upright_prior_weight() * (frame.prior_up - frame.rotation.col(2)).squaredNorm();
      }
    });
    double sum = 0;
    for (double part : chunk_sum) sum += part;
    for (std::size_t u = 0; u < used_.size(); ++u) {
      const std::size_t m = static_cast<std::size_t>(used_[u]);
      sum += offset_prior_[u] * (model.markers[m].offset - start_.markers[m].offset).squaredNorm();
    }
    for (double c : cumulative) sum += scale_weight_ * (c - 1) * (c - 1);
    if (shrink_.size() > 0) {
      const Eigen::VectorXd e = offset_deviation(model);
      sum += e.dot(shrink_ * e);
    }
    return sum;
  }

  /// The frames the posture's prior holds, counted by their weights; at least 1.
  static double posture_prior_frames(const std::vector<BundleFrame>& frames) {
    double count = 0;
    for (const BundleFrame& frame : frames)
      if (holds_posture_prior(frame)) count += frame.weight;
    return std::max(count, 1.0);
  }

  /// The frames that share one prior's weight: the static trial's with static_posture_estimated,
  /// else each frame has its own.
  double prior_sharing_frames() const { return options_.static_posture_estimated ? pose_prior_frames_ : 1.0; }

  /// Per frame of weight 1.
  double pose_prior_weight() const {
    return 1.0 / (options_.static_pose_sd_rad * options_.static_pose_sd_rad * prior_sharing_frames());
  }

  /// Per frame of weight 1, shared over the frames as the posture's prior is.
  double upright_prior_weight() const {
    return 1.0 / (options_.static_upright_sd_rad * options_.static_upright_sd_rad * prior_sharing_frames());
  }

  /// The used markers' offsets minus the marker set's, stacked as the subject unknowns order them.
  Eigen::VectorXd offset_deviation(const body::BodyModel& model) const {
    Eigen::VectorXd e(3 * static_cast<Eigen::Index>(used_.size()));
    for (std::size_t u = 0; u < used_.size(); ++u) {
      const std::size_t m = static_cast<std::size_t>(used_[u]);
      e.segment<3>(3 * static_cast<Eigen::Index>(u)) = model.markers[m].offset - start_.markers[m].offset;
    }
    return e;
  }

  /// One frame's normal equations: A (pose x pose), B^T (subject x pose: the rows beneath A in the
  /// elimination's panel, copied without a transposition), the pose gradient g, and
  /// the frame's share of the subject block C and gradient h (added to them). Pose columns are
  /// [root position, rotation vector on the right of the root rotation, joints].
  void linearise(const body::BodyModel& model, const BundleFrame& frame, Eigen::MatrixXd& A,
                 Eigen::MatrixXd& Bt, Eigen::VectorXd& g, Eigen::MatrixXd& C, Eigen::VectorXd& h) const {
    const int n = kRoot + model.joint_count();
    A.setZero(n, n);
    Bt.setZero(unknowns_, n);
    g.setZero(n);
    const body::FrameTransforms tf = body::joint_frames(model, frame.position, frame.rotation, frame.joints);
    const auto y = recording_.frame(frame.index);
    Eigen::Matrix<double, 3, Eigen::Dynamic> jq(3, n), js(3, scales_);
    std::vector<int> active;  // the columns of jq a marker moves: the root's and its chain's joints
    active.reserve(static_cast<std::size_t>(n));
    std::vector<int> scaled;  // the length factors that move it (js's non-zero columns)
    scaled.reserve(static_cast<std::size_t>(std::max(scales_, 0)));
    for (int u : frame.markers) {
      const int m = used_[static_cast<std::size_t>(u)];
      const double w = frame.weight * weight_[static_cast<std::size_t>(u)];
      const body::Marker& marker = model.markers[static_cast<std::size_t>(m)];
      const auto mf = static_cast<std::size_t>(marker.frame);
      const Eigen::Vector3d p = tf.origins[mf] + tf.rotations[mf] * marker.offset;
      const Eigen::Vector3d r = y.col(mapping_.point_of_marker[static_cast<std::size_t>(m)]) - p;
      jq.setZero();
      js.setZero();
      jq.leftCols<3>().setIdentity();
      const Eigen::Vector3d arm = p - frame.position;
      for (int k = 0; k < 3; ++k) jq.col(3 + k) = frame.rotation.col(k).cross(arm);  // R <- R Exp(omega)
      active.assign({0, 1, 2, 3, 4, 5});
      scaled.clear();
      for (int f = marker.frame; f > 0; f = model.joints[static_cast<std::size_t>(f - 1)].parent_frame) {
        const body::Joint& joint = model.joints[static_cast<std::size_t>(f - 1)];
        const auto fs = static_cast<std::size_t>(f);
        jq.col(kRoot + f - 1) = tf.rotations[fs].col(static_cast<int>(joint.axis)).cross(p - tf.origins[fs]);
        active.push_back(kRoot + f - 1);
        const int s = joint_scale_[static_cast<std::size_t>(f - 1)];
        if (s >= 0) {
          if (std::find(scaled.begin(), scaled.end(), s) == scaled.end()) scaled.push_back(s);
          js.col(s) += tf.rotations[static_cast<std::size_t>(joint.parent_frame)] * joint.translation;
        }
      }
      const Eigen::Matrix3d& ro = tf.rotations[mf];  // d p / d offset
      const int at = scales_ + 3 * u;
      // A += w jq^T jq, g += w jq^T r, B += w jq^T [js ro] over the active columns only: the
      // others of jq and js are exactly zero (a marker moves with the root and its own chain, about
      // 16 of the 46 columns, and with the length factors along that chain), so this is the dense
      // product's result at a tenth of its work, in fixed-size products (Eigen's general product
      // for every marker's 3 x 12 blocks cost more than the sums themselves).
      for (const int a : active) {
        const Eigen::Vector3d ja = w * jq.col(a);
        for (const int b : active) A(b, a) += ja.dot(jq.col(b));
        g(a) += ja.dot(r);
        Bt.block<3, 1>(at, a) += ro.transpose() * ja;
        for (const int s : scaled) Bt(s, a) += ja.dot(js.col(s));
      }
      h.segment<3>(at).noalias() += w * ro.transpose() * r;
      C.block<3, 3>(at, at).diagonal().array() += w;
      for (const int s : scaled) {
        const Eigen::Vector3d js_w = w * js.col(s);
        for (const int t : scaled) C(t, s) += js_w.dot(js.col(t));
        C.block<1, 3>(s, at) += js_w.transpose() * ro;
        C.block<3, 1>(at, s) += ro.transpose() * js_w;
        h(s) += js_w.dot(r);
      }
    }
    // The static posture's prior on the joint angles (its Jacobian is the identity).
    if (holds_posture_prior(frame)) {
      const double w = frame.weight * pose_prior_weight();
      for (int j = 0; j < model.joint_count(); ++j) {
        A(kRoot + j, kRoot + j) += w;
        g(kRoot + j) += w * (frame.prior_joints(j) - frame.joints(j));
      }
    }
    // The upright prior on the root's vertical axis R e_z: R Exp(w) e_z = R e_z + R (w_y, -w_x, 0).
    if (holds_upright(frame)) {
      const double w = frame.weight * upright_prior_weight();
      Eigen::Matrix3d jr;
      jr.col(0) = -frame.rotation.col(1);
      jr.col(1) = frame.rotation.col(0);
      jr.col(2).setZero();
      const Eigen::Vector3d r = frame.prior_up - frame.rotation.col(2);
      A.block<3, 3>(3, 3).noalias() += w * jr.transpose() * jr;
      g.segment<3>(3).noalias() += w * jr.transpose() * r;
    }
    // Active set: a joint on a limit that the gradient pushes further out stays there for this
    // step (clamping a free step afterwards would spoil the rest of it).
    for (int j = 0; j < model.joint_count(); ++j) {
      const double q = frame.joints(j), gj = g(kRoot + j);
      const body::Joint& joint = model.joints[static_cast<std::size_t>(j)];
      if ((q <= joint.lower && gj < 0) || (q >= joint.upper && gj > 0)) {
        A.row(kRoot + j).setZero();
        A.col(kRoot + j).setZero();
        A(kRoot + j, kRoot + j) = 1;
        Bt.col(kRoot + j).setZero();
        g(kRoot + j) = 0;
      }
    }
  }

  /// Every frame's blocks at one linearisation point (reused by the attempts that search the
  /// damping): about 80 KB per frame, 25 MB for the 300 frames of a 1200-frame calibration.
  struct NormalEquations {
    std::vector<Eigen::MatrixXd> A, Bt;
    std::vector<Eigen::VectorXd> g;
    Eigen::MatrixXd C;
    Eigen::VectorXd h;
  };

  void linearise_all(const body::BodyModel& model, const std::vector<BundleFrame>& frames,
                     NormalEquations& normal) const {
    normal.A.resize(frames.size());
    normal.Bt.resize(frames.size());
    normal.g.resize(frames.size());
    std::vector<Eigen::MatrixXd> C(kCalibrationChunks, Eigen::MatrixXd::Zero(unknowns_, unknowns_));
    std::vector<Eigen::VectorXd> h(kCalibrationChunks, Eigen::VectorXd::Zero(unknowns_));
    parallel_for(kCalibrationChunks, options_.threads, [&](int c) {
      const auto [begin, end] = chunk_range(frames.size(), c);
      const auto at = static_cast<std::size_t>(c);
      for (std::size_t k = begin; k < end; ++k)
        linearise(model, frames[k], normal.A[k], normal.Bt[k], normal.g[k], C[at], h[at]);
    });
    normal.C = C[0];
    normal.h = h[0];
    for (std::size_t c = 1; c < C.size(); ++c) normal.C += C[c], normal.h += h[c];
  }

  /// The subject's information from the data alone: the reduced normal matrix of the bundle
  /// adjustment without priors or damping (the poses eliminated frame by frame), full.
  Eigen::MatrixXd data_information(const NormalEquations& normal) const {
    Eigen::MatrixXd information = normal.C;
    Eigen::VectorXd unused = Eigen::VectorXd::Zero(unknowns_);
    BorderedCholesky panel;
    Eigen::MatrixXd factor;
    for (std::size_t k = 0; k < normal.A.size(); ++k)  // the floor alone: unseen directions stay solvable
      eliminate_pose(normal, k, 0, panel, factor, information, unused);
    information.triangularView<Eigen::StrictlyUpper>() = information.transpose();
    return information;
  }

  /// Eliminates frame k's pose from the normal equations: A + damping = L L^T (`factor` receives
  /// L) and the frame's share of the reduced system, -X^T X into the lower half of `reduced` and
  /// -X^T z into `rhs` (X = L^-1 B, z = L^-1 g). [A; B^T; g^T] is factorised in one pass into
  /// [L; X^T; z^T] in the tiles compiled for the processor (Eigen's LLT and triangular solve took
  /// twice as long). False if the damped A is not positive definite.
  bool eliminate_pose(const NormalEquations& normal, std::size_t k, double damping, BorderedCholesky& panel,
                      Eigen::MatrixXd& factor, Eigen::MatrixXd& reduced, Eigen::VectorXd& rhs) const {
    factor = normal.A[k];
    damp(factor, damping);
    const Eigen::Index n = factor.rows();
    panel.resize(n, unknowns_ + 1);
    auto p = panel.panel();
    p.topRows(n) = factor;
    p.middleRows(n, unknowns_) = normal.Bt[k];
    p.row(n + unknowns_) = normal.g[k].transpose();
    if (!panel.factorise()) return false;
    factor = p.topRows(n).triangularView<Eigen::Lower>();
    const auto xt = p.middleRows(n, unknowns_);
    add_self_product_lower(reduced, xt, -1.0);
    rhs.noalias() -= xt * p.row(n + unknowns_).transpose();
    return true;
  }

  /// data_information in the prior's metric (information_in_prior_metric), at the current
  /// scale_weight_; `prior_sd` receives the prior SDs.
  Eigen::MatrixXd whitened_information(const NormalEquations& normal, Eigen::VectorXd& prior_sd) const {
    prior_sd.resize(unknowns_);
    for (int s = 0; s < scales_; ++s) prior_sd(s) = 1.0 / std::sqrt(scale_weight_);
    for (std::size_t u = 0; u < used_.size(); ++u)
      prior_sd.segment<3>(scales_ + 3 * static_cast<int>(u)).setConstant(1.0 / std::sqrt(offset_prior_[u]));
    return prior_sd.asDiagonal() * data_information(normal) * prior_sd.asDiagonal();
  }

  /// Sets `estimated_`, the basis of the subject directions the bundle adjustment moves: in the
  /// prior's metric (unknowns scaled by their prior SDs), the eigenvectors of the data information
  /// whose eigenvalue (information from the data over the prior's) reaches prior_only_fraction of
  /// a marker coordinate's seen in all `frames`. The others keep the marker set's values; they are
  /// listed in `pass`.
  void choose_estimated_directions(const body::BodyModel& model, const NormalEquations& normal,
                                   std::size_t frames, CalibrationPass& pass) {
    estimated_.resize(0, 0);
    if (options_.prior_only_fraction <= 0) return;
    Eigen::VectorXd prior_sd;
    const Eigen::MatrixXd information = whitened_information(normal, prior_sd);
    Eigen::VectorXd ratios;
    Eigen::MatrixXd vectors;
    double threshold = options_.prior_only_fraction;
    if (options_.prior_only_share) {
      // S v = mu (C + P) v in the prior's metric (P = I): mu is the share of what the data would
      // tell with the poses known, plus the prior, that survives the poses' elimination.
      Eigen::MatrixXd known = prior_sd.asDiagonal() * normal.C * prior_sd.asDiagonal();
      known.diagonal().array() += 1.0;
      const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eigen(information, known);
      if (eigen.info() != Eigen::Success) return;  // estimate every direction, as without the option
      ratios = eigen.eigenvalues();
      vectors = eigen.eigenvectors();
    } else {
      threshold = prior_only_threshold(options_.prior_only_fraction, frames);
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(information);
      if (eigen.info() != Eigen::Success) return;
      ratios = eigen.eigenvalues();
      vectors = eigen.eigenvectors();
    }
    std::vector<Eigen::Index> kept;
    for (Eigen::Index i = 0; i < unknowns_; ++i) {
      const double ratio = ratios(i);
      if (ratio >= threshold) {
        kept.push_back(i);
        continue;
      }
      // Where it lies: shares of the unit eigenvector by segment.
      const Eigen::VectorXd v = vectors.col(i).normalized();
      std::map<std::string, double> share;
      for (int s = 0; s < scales_; ++s) share[segments_[static_cast<std::size_t>(s)]] += v(s) * v(s);
      for (std::size_t u = 0; u < used_.size(); ++u)
        share[body::segment_of_frame(model, model.markers[static_cast<std::size_t>(used_[u])].frame)] +=
            v.segment<3>(scales_ + 3 * static_cast<int>(u)).squaredNorm();
      const auto largest = std::max_element(share.begin(), share.end(),
                                            [](const auto& a, const auto& b) { return a.second < b.second; });
      pass.prior_only.push_back({ratio, largest->first, largest->second});
    }
    estimated_.resize(unknowns_, static_cast<Eigen::Index>(kept.size()));
    for (std::size_t c = 0; c < kept.size(); ++c)
      estimated_.col(static_cast<Eigen::Index>(c)) = prior_sd.asDiagonal() * vectors.col(kept[c]);
  }

  /// Sets `shrink_`, the weak-direction shrinkage prior c (C + P) on the offsets (the offsets'
  /// block of the subject unknowns; CalibrationOptions::weak_direction_shrink), from the first
  /// linearisation.
  void choose_shrinkage(const NormalEquations& normal) {
    shrink_.resize(0, 0);
    if (options_.weak_direction_shrink <= 0) return;
    const int offsets = unknowns_ - scales_;
    shrink_ = normal.C.bottomRightCorner(offsets, offsets);
    for (std::size_t u = 0; u < used_.size(); ++u)
      shrink_.block<3, 3>(3 * static_cast<int>(u), 3 * static_cast<int>(u)).diagonal().array() +=
          offset_prior_[u];
    shrink_ *= options_.weak_direction_shrink;
    // Placed markers are not pulled towards the template fit's guess (C is block diagonal per marker).
    for (std::size_t u = 0; u < used_.size(); ++u) {
      if (!placed_[u]) continue;
      const auto at = 3 * static_cast<Eigen::Index>(u);
      shrink_.middleRows(at, 3).setZero();
      shrink_.middleCols(at, 3).setZero();
    }
  }

  /// A's Levenberg-Marquardt damping: relative to its diagonal, with a floor that keeps the
  /// directions no marker sees (exactly redundant spine and neck pairs, joints of hidden
  /// segments) solvable without moving them.
  static void damp(Eigen::MatrixXd& A, double damping) {
    const double floor = 1e-9 * std::max(A.diagonal().maxCoeff(), 1e-12);
    A.diagonal() += (damping * A.diagonal().array() + floor).matrix();
  }

  /// One damped Gauss-Newton step from (model, frames): the subject step from the reduced
  /// (Schur complement) system, then each frame's pose step. False if a system is not solvable.
  bool step(const body::BodyModel& model, const NormalEquations& normal, double damping,
            body::BodyModel& trial_model, std::vector<BundleFrame>& trial_frames,
            std::vector<double>& trial_cumulative) const {
    Eigen::MatrixXd C = normal.C;
    Eigen::VectorXd h = normal.h;
    // Each chunk of frames: its factors and its share of the reduced system, added in chunk order.
    std::vector<Eigen::MatrixXd> chunk_reduced(kCalibrationChunks,
                                               Eigen::MatrixXd::Zero(unknowns_, unknowns_));
    std::vector<Eigen::VectorXd> chunk_rhs(kCalibrationChunks, Eigen::VectorXd::Zero(unknowns_));
    std::vector<char> solvable(kCalibrationChunks, 1);
    std::vector<Eigen::MatrixXd> factors(normal.A.size());  // each frame's L, A + damping = L L^T
    parallel_for(kCalibrationChunks, options_.threads, [&](int c) {
      const auto [begin, end] = chunk_range(normal.A.size(), c);
      const auto at = static_cast<std::size_t>(c);
      BorderedCholesky panel;
      for (std::size_t k = begin; k < end && solvable[at]; ++k)
        if (!eliminate_pose(normal, k, damping, panel, factors[k], chunk_reduced[at], chunk_rhs[at]))
          solvable[at] = 0;
    });
    if (std::find(solvable.begin(), solvable.end(), 0) != solvable.end()) return false;
    Eigen::MatrixXd reduced = chunk_reduced[0];
    Eigen::VectorXd reduced_rhs = chunk_rhs[0];
    for (std::size_t c = 1; c < chunk_reduced.size(); ++c) {
      reduced.triangularView<Eigen::Lower>() += chunk_reduced[c];
      reduced_rhs += chunk_rhs[c];
    }
    // Priors (offsets towards the start, length factors towards 1), then the damping.
    for (std::size_t u = 0; u < used_.size(); ++u) {
      const std::size_t m = static_cast<std::size_t>(used_[u]);
      const int at = scales_ + 3 * static_cast<int>(u);
      C.block<3, 3>(at, at).diagonal().array() += offset_prior_[u];
      h.segment<3>(at) -= offset_prior_[u] * (model.markers[m].offset - start_.markers[m].offset);
    }
    const double scale_weight = scale_weight_;
    for (int s = 0; s < scales_; ++s) {
      const double c = cumulative_[static_cast<std::size_t>(s)];
      C(s, s) += scale_weight * c * c;
      h(s) -= scale_weight * c * (c - 1.0);
    }
    if (shrink_.size() > 0) {  // the shrinkage prior on the offsets' deviation (Jacobian I)
      const int offsets = unknowns_ - scales_;
      C.bottomRightCorner(offsets, offsets) += shrink_;
      h.tail(offsets) -= shrink_ * offset_deviation(model);
    }
    damp(C, damping);
    reduced.triangularView<Eigen::Lower>() += C;
    reduced_rhs += h;
    Eigen::VectorXd subject_step;
    if (estimated_.size() == 0) {
      const Eigen::LDLT<Eigen::MatrixXd> reduced_factor(reduced);  // reads the lower triangle
      subject_step = reduced_factor.solve(reduced_rhs);
      if (reduced_factor.info() != Eigen::Success) return false;
    } else {  // the step restricted to the estimated directions: subject_step = E y
      const Eigen::MatrixXd restricted =
          estimated_.transpose() * reduced.selfadjointView<Eigen::Lower>() * estimated_;
      const Eigen::LDLT<Eigen::MatrixXd> restricted_factor(restricted);
      subject_step = estimated_ * restricted_factor.solve(estimated_.transpose() * reduced_rhs);
      if (restricted_factor.info() != Eigen::Success) return false;
    }
    if (!subject_step.allFinite()) return false;

    // Back-substitution: each frame's pose step given the subject step.
    std::vector<char> finite(kCalibrationChunks, 1);
    parallel_for(kCalibrationChunks, options_.threads, [&](int c) {
      const auto [begin, end] = chunk_range(trial_frames.size(), c);
      for (std::size_t k = begin; k < end; ++k) {
        Eigen::VectorXd pose_step = normal.g[k];  // A^-1 (g - B s)
        pose_step.noalias() -= normal.Bt[k].transpose() * subject_step;
        factors[k].triangularView<Eigen::Lower>().solveInPlace(pose_step);
        factors[k].triangularView<Eigen::Lower>().transpose().solveInPlace(pose_step);
        if (!step_frame(model, pose_step, trial_frames[k])) finite[static_cast<std::size_t>(c)] = 0;
      }
    });
    if (std::find(finite.begin(), finite.end(), 0) != finite.end()) return false;
    for (int j = 0; j < trial_model.joint_count(); ++j) {
      const int s = joint_scale_[static_cast<std::size_t>(j)];
      if (s >= 0) trial_model.joints[static_cast<std::size_t>(j)].translation *= 1.0 + subject_step(s);
    }
    for (int s = 0; s < scales_; ++s) trial_cumulative[static_cast<std::size_t>(s)] *= 1.0 + subject_step(s);
    for (std::size_t u = 0; u < used_.size(); ++u)
      trial_model.markers[static_cast<std::size_t>(used_[u])].offset +=
          subject_step.segment<3>(scales_ + 3 * static_cast<int>(u));
    return true;
  }

  /// Moves one frame's pose by its step (joints kept inside their limits); false if the step is
  /// not finite.
  static bool step_frame(const body::BodyModel& model, const Eigen::VectorXd& pose_step, BundleFrame& frame) {
    if (!pose_step.allFinite()) return false;
    frame.position += pose_step.head<3>();
    const Eigen::Vector3d omega = pose_step.segment<3>(3);
    if (omega.norm() > 0)
      frame.rotation =
          frame.rotation * Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix();
    for (int j = 0; j < model.joint_count(); ++j)
      frame.joints(j) =
          std::clamp(frame.joints(j) + pose_step(kRoot + j), model.joints[static_cast<std::size_t>(j)].lower,
                     model.joints[static_cast<std::size_t>(j)].upper);
    return true;
  }

  const body::BodyModel& start_;
  const body::MarkerMapping& mapping_;
  const MarkerSequence& recording_;
  const CalibrationOptions& options_;
  std::vector<std::string> segments_;
  std::vector<double> cumulative_;
  std::vector<int> used_;
  std::vector<int> joint_scale_;
  std::vector<double> weight_, offset_prior_;
  std::vector<bool> placed_;  ///< per used marker: placed by its motion, with a static trial
  double noise_variance_ = 1;
  Eigen::MatrixXd estimated_;  ///< basis of the subject directions adjusted; empty: all of them
  Eigen::MatrixXd shrink_;     ///< the weak-direction shrinkage prior on the offsets; empty: none
  int scales_ = 0, unknowns_ = 0;
  double scale_weight_ = 0;
  /// The static trial's frames the adjustment holds, counted by their weights (they share the
  /// posture's prior).
  double pose_prior_frames_ = 1;
};

}  // namespace detail
}  // namespace s2kf::calibration
