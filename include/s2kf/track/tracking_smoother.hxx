/// @file
/// The definitions of <s2kf/track/tracking_smoother.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/track/tracking_smoother.hpp>

namespace s2kf::track {
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

}  // namespace s2kf::track
