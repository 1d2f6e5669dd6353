/// @file
/// The whole-body tracker: streams marker frames through the S2KF with the
/// bounded-joint marker model and reports the pose per frame. No file I/O;
/// frame by frame, for live systems too.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/bounded_joints.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/marker_measurement_model.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/core/marginal_update.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>
#include <s2kf/geometry/rigid_fit.hpp>
#include <s2kf/track/state_chart.hpp>
#include <s2kf/track/tracker_options.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::track {

/// Why a marker the recording shows was left out of a frame's update.
enum class MarkerRejection : std::uint8_t {
  none,
  innovation,  ///< improbable under its predicted covariance (a swapped,
               ///< mislabelled or jumping marker)
  frozen,      ///< its coordinates repeat exactly while the body moves (a stuck
               ///< marker)
};

/// What the tracker knows after one frame.
struct FrameEstimate {
  bool tracked = false;  ///< false before the first frame with enough markers
  FilterStatus status = FilterStatus::nothing_observed;
  body::Pose pose;  ///< root position (mm), roll/pitch/yaw (rad), joint angles (rad)
  Eigen::Matrix3d root_rotation = Eigen::Matrix3d::Identity();
  Eigen::MatrixXd covariance;          ///< 46 x 46: position, orientation error (rad), Theta
  Eigen::Matrix3Xd predicted_markers;  ///< every model marker at the estimated pose (mm)
  Eigen::VectorXd marker_distance;     ///< per model marker, mm; NaN where not observed
  double mean_marker_distance = std::numeric_limits<double>::quiet_NaN();
  int visible_markers = 0;  ///< mapped markers observed this frame
  /// Per model marker: none, or why the marker was seen but left out of this
  /// frame's update.
  std::vector<MarkerRejection> rejection;
  int rejected_markers = 0;  ///< markers left out this frame (rejection != none)
  double nis = std::numeric_limits<double>::quiet_NaN();
  double seconds = 0;  ///< time spent in process()
};

/// Tracks one subject. State x = [root position (3), orientation error (3),
/// Theta (joints)], where the orientation error is a rotation vector about the
/// current estimate (R = R_ref Exp(delta)), folded into R_ref after every
/// update: the filter never sees the roll-pitch-yaw singularity, so the root
/// can turn through any rotation. Joint angles are theta = bounded(Theta),
/// inside their limits for every Theta.
class Tracker {
 public:
  static constexpr int kRootDofs = kFirstJointState;

  /// `samples` is the S2KF's sample set for state_dimension() (6 + joints)
  /// dimensions, e.g. lcd_sample_set(46, options.samples).set from the cache
  /// (sample_cache.hpp): where sample sets come from is the caller's business,
  /// so the tracker does no file I/O. Options are checked first:
  /// std::invalid_argument (one sentence) before any work.
  Tracker(body::BodyModel model, body::MarkerMapping mapping, TrackerOptions options, double rate_hz,
          const SampleSet& samples);

  int joint_count() const { return model_.joint_count(); }
  int state_dimension() const { return kRootDofs + model_.joint_count(); }
  /// The whole state the motion model moves: the pose (state_dimension()), and
  /// with the constant-velocity model its rate of change as well (twice as
  /// many).
  int motion_state_dimension() const { return with_rates() ? 2 * state_dimension() : state_dimension(); }
  bool with_rates() const { return options_.motion_model == MotionModel::constant_velocity; }
  const body::BodyModel& model() const { return model_; }
  const body::MarkerMapping& mapping() const { return mapping_; }
  const TrackerOptions& options() const { return options_; }
  bool initialised() const { return initialised_; }
  const FrameEstimate& estimate() const { return estimate_; }
  /// The model markers the recording supplies, in the order the measurement stacks them: body
  /// part by body part (see body_part_of_frame), the model's order within a part.
  const std::vector<int>& used_markers() const { return used_markers_; }
  int frames_processed() const { return frames_; }
  /// The filter's posterior after the last frame: [root position (mm),
  /// orientation error about reference_rotation() (rad, zero after an update),
  /// Theta (40)]; what offline smoothing keeps.
  const GaussianXd& state() const { return state_; }
  /// The posterior of the whole state after the last frame: state() with, for
  /// the constant-velocity model, the rates (reference_rotation()'s axes, per
  /// second) appended.
  const GaussianXd& motion_state() const { return with_rates() ? motion_ : state_; }
  const Eigen::Matrix3d& reference_rotation() const { return reference_rotation_; }
  /// The prediction between two frames: x <- transition() x + w, w ~ N(0,
  /// process_noise()), on the motion state (identity for the random walk).
  const Eigen::MatrixXd& process_noise() const { return process_noise_; }
  const Eigen::MatrixXd& transition() const { return transition_; }

  /// One frame: the recording's points (3 x P, mm, in recording order) and
  /// which are visible. Non-finite coordinates count as not visible.
  const FrameEstimate& process(const Eigen::Matrix3Xd& points,
                               const Eigen::Array<bool, Eigen::Dynamic, 1>& visible);

 private:
  static TrackerOptions validated(TrackerOptions options, double rate_hz) {
    options.validate();
    if (!(rate_hz > 0) || !std::isfinite(rate_hz))
      throw std::invalid_argument("the frame rate must be positive");
    return options;
  }

  static const SampleSet& checked(const SampleSet& samples, int dimension) {
    if (samples.dimension() != dimension)
      throw std::invalid_argument("the sample set has " + std::to_string(samples.dimension()) +
                                  " dimensions; the tracker's state has " + std::to_string(dimension));
    return samples;
  }

  /// The body part a frame belongs to, for the information form's groups: the subtree of the
  /// root's child joint it descends from (for the MMM model the upper body, from the lumbar spine
  /// up to the head and the hands, and each leg), the root's own markers (the pelvis) a part of
  /// their own. The nonlinear parts of the predictions are correlated within a part: every marker
  /// of the upper body moves with the spine's joints, every marker of a leg with its hip. Across
  /// parts only the root's pose is shared, which the filter's local rotation error keeps nearly
  /// linear. Finer parts (each arm apart from the spine) would leave out the spine's share of the
  /// arms' markers.
  static int body_part_of_frame(const body::BodyModel& model, int frame) {
    while (frame > 0 && model.joints[static_cast<std::size_t>(frame - 1)].parent_frame != 0)
      frame = model.joints[static_cast<std::size_t>(frame - 1)].parent_frame;
    return frame;
  }

  /// Start from the first frame with enough markers: root pose from a rigid fit
  /// of the visible markers to the model's zero pose (or the paper's marker
  /// mean), joints near the zero pose.
  void initialise(const Eigen::Matrix3Xd& points);

  /// x <- A x + w with A = [I dt I; 0 I] (transition()), written out by blocks:
  /// the same result as the core's predict_linear (a test compares them) in
  /// O(n^2) rather than two dense 92 x 92 products, which would cost more than
  /// the rest of a frame at L = 301.
  void predict_constant_velocity();

  /// The measurement sees the pose only: the rates follow the pose's correction
  /// by linear-Gaussian conditioning (core/marginal_update.hpp), exact for the
  /// Gaussian prior, where sampling the doubled state would double the sample
  /// dimension. A failed factorisation keeps the rates as predicted, with the
  /// pose part replaced.
  void condition_rates();

  /// TrackerOptions::axial_split_sd_rad: for each pair of stacked twists (a,
  /// b), the linearised pseudo-measurement 0 = theta_a - theta_b + v, v ~ N(0,
  /// sd^2), as an exact Kalman update of the pose (a rank-one change of its
  /// covariance).
  void split_axial_twists();

  /// Folds the orientation error into the reference and every Theta onto the
  /// principal branch (state_chart.hpp); with rates, the orientation rate turns
  /// with the reference and a reflected Theta's rate changes sign.
  void recentre();

  void finish(const Eigen::Matrix3Xd& points, const Eigen::Array<bool, Eigen::Dynamic, 1>& visible,
              std::chrono::steady_clock::time_point start);

  /// measurement_model_.pose(state_.mean) written in place (that one returns
  /// its joint angles in a new vector), through the same bounded map.
  void write_pose(body::Pose& pose) const;

  body::BodyModel model_;
  body::MarkerMapping mapping_;
  TrackerOptions options_;
  double rate_hz_;
  SmartSamplingKalmanFilter<Eigen::Dynamic> filter_;
  body::MarkerMeasurementModel measurement_model_;
  std::vector<int> used_markers_;        ///< model markers in the measurement, body part by body part
  std::vector<int> information_groups_;  ///< per measurement component: its marker's body part
  std::vector<std::vector<int>> marker_dependencies_;  ///< per used marker: the states it reads
  /// The state's orientation error (3-5): every body part hangs from it, so the second order of
  /// its error is the nonlinearity the parts share (UpdateOptions::information_quadratic_states).
  std::vector<int> root_orientation_states_ = {3, 4, 5};
  GaussianXd state_;   ///< the pose posterior (what the update works on)
  GaussianXd motion_;  ///< constant velocity: [pose, rates]; its pose part
                       ///< equals state_ between frames
  MarginalUpdate marginal_update_;
  Eigen::Matrix3d reference_rotation_ = Eigen::Matrix3d::Identity();
  Eigen::MatrixXd process_noise_, transition_, noise_;
  std::vector<std::pair<int, int>> axial_pairs_;  ///< joints (a, b) whose twists only add up
  Eigen::VectorXd axial_gain_, axial_column_;     ///< scratch of split_axial_twists
  std::vector<int> repeat_frames_;                ///< per used marker: frames its coordinates
                                                  ///< have repeated exactly
  int frozen_frames_ = 0;                         ///< frozen_marker_s in frames
  Eigen::VectorXd measurement_;
  ObservedMask observed_;
  FrameEstimate estimate_;
  bool initialised_ = false;
  int frames_ = 0;
  int frames_since_start_ = 0;
};

}  // namespace s2kf::track

#if !defined(S2KF_COMPILED)
#include <s2kf/track/tracker.hxx>
#endif
