/// @file
/// Offline smoothing of a tracked recording (`s2kf track --smooth`): the tracker's posterior is kept
/// after every frame (with the rates, for the constant-velocity model), then a Rauch-Tung-Striebel
/// pass runs backwards over them. The smoother works
/// on the bounded joint parameters Theta, like the filter, so every joint stays within its limits.
#pragma once

#include <s2kf/body/bounded_joints.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/core/rts_smoother.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/track/state_chart.hpp>
#include <s2kf/track/tracker.hpp>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace s2kf::track {

class TrackingSmoother {
 public:
  explicit TrackingSmoother(const Tracker& tracker)
      : joints_(tracker.model()),
        transition_(tracker.transition()),
        process_noise_(tracker.process_noise()),
        with_rates_(tracker.with_rates()) {}

  /// Memory one recorded frame takes (mean, covariance and reference rotation of the 46-state);
  /// the constant-velocity model keeps the 92-state, bytes_per_frame(true), four times as much.
  static constexpr std::size_t kBytesPerFrame = (46 + 46 * 46 + 9) * sizeof(double);
  static constexpr std::size_t bytes_per_frame(bool with_rates) {
    return with_rates ? (92 + 92 * 92 + 9) * sizeof(double) : kBytesPerFrame;
  }

  /// Keeps the tracker's posterior after the frame that is row `row` of the motion table. Call it
  /// after every tracker.process(); frames before tracking starts are skipped.
  void record(const Tracker& tracker, Eigen::Index row);

  std::size_t frames() const { return states_.size(); }

  /// Replaces the rows of the recorded frames in `motion` (root position, roll/pitch/yaw, joint
  /// angles) by the smoothed poses.
  void smooth(io::MotionTable& motion) const;

 private:
  /// Step k+1's chart differs from step k's by the tracker's re-centring (state_chart.hpp).
  void to_chart_of(std::size_t k, Eigen::VectorXd& mean, Eigen::MatrixXd& covariance) const;

  body::BoundedJoints joints_;
  Eigen::MatrixXd transition_, process_noise_;
  bool with_rates_ = false;
  std::vector<GaussianXd> states_;
  std::vector<Eigen::Matrix3d> references_;
  std::vector<Eigen::Index> rows_;
};

#if S2KF_DEFINE_HEAVY
S2KF_INLINE void TrackingSmoother::smooth(io::MotionTable& motion) const {
  const std::vector<GaussianXd> smoothed =
      rts_smooth_linear(states_, transition_, process_noise_,
                        [this](std::size_t k, Eigen::VectorXd& mean, Eigen::MatrixXd& covariance) {
                          to_chart_of(k, mean, covariance);
                        });
  const Eigen::Index joints = joints_.size();
  for (std::size_t k = 0; k < smoothed.size(); ++k) {
    const Eigen::VectorXd& m = smoothed[k].mean;
    const Eigen::Index row = rows_[k];
    if (row < 0 || row >= motion.values.rows() || motion.values.cols() != 6 + joints)
      throw std::invalid_argument(
          "TrackingSmoother::smooth: the motion table does not hold the recorded frames");
    motion.values.row(row).head<3>() = m.head<3>().transpose();
    motion.values.row(row).segment<3>(3) =
        body::rpy_from_rotation(chart_rotation(references_[k], m.segment<3>(3))).transpose();
    // A smoothed Theta beyond +-pi/2 says the joint is, if anything, further towards its limit
    // than the filter (which keeps Theta inside) had it: the sine would reflect it back into the
    // range, so it is held at the limit instead.
    const Eigen::VectorXd theta = m.segment(kFirstJointState, joints).cwiseMax(-kPi / 2).cwiseMin(kPi / 2);
    motion.values.row(row).tail(joints) = joints_.angles(theta).transpose();
  }
}
S2KF_INLINE void TrackingSmoother::record(const Tracker& tracker, Eigen::Index row) {
  if (!tracker.estimate().tracked) return;
  if (!rows_.empty() && row != rows_.back() + 1)
    throw std::invalid_argument("TrackingSmoother::record: tracked frames must come one after another");
  if (tracker.motion_state().dimension() != process_noise_.rows())
    throw std::invalid_argument(
        "TrackingSmoother::record: the tracker is not the one the smoother was made for");
  states_.push_back(tracker.motion_state());
  references_.push_back(tracker.reference_rotation());
  rows_.push_back(row);
}

S2KF_INLINE void TrackingSmoother::to_chart_of(std::size_t k, Eigen::VectorXd& mean,
                                               Eigen::MatrixXd& covariance) const {
  to_previous_chart(references_[k], references_[k + 1], states_[k].mean, mean, covariance, with_rates_);
}

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::track
