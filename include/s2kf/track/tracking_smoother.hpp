/// @file
/// Offline smoothing of a tracked recording (`s2kf track --smooth`): the tracker's posterior is kept
/// after every frame, then a Rauch-Tung-Striebel pass runs backwards over them. The smoother works
/// on the bounded joint parameters Theta, like the filter, so every joint stays within its limits.
#pragma once

#include <s2kf/body/bounded_joints.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/rts_smoother.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/track/tracker.hpp>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace s2kf::track {

class TrackingSmoother {
 public:
  explicit TrackingSmoother(const Tracker& tracker)
      : joints_(tracker.model()), process_noise_(tracker.process_noise()) {}

  /// Memory one recorded frame takes (mean, covariance and reference rotation of the 46-state).
  static constexpr std::size_t kBytesPerFrame = (46 + 46 * 46 + 9) * sizeof(double);

  /// Keeps the tracker's posterior after the frame that is row `row` of the motion table. Call it
  /// after every tracker.process(); frames before tracking starts are skipped.
  void record(const Tracker& tracker, Eigen::Index row) {
    if (!tracker.estimate().tracked) return;
    if (!rows_.empty() && row != rows_.back() + 1)
      throw std::invalid_argument("TrackingSmoother::record: tracked frames must come one after another");
    if (tracker.state().dimension() != process_noise_.rows())
      throw std::invalid_argument(
          "TrackingSmoother::record: the tracker is not the one the smoother was made for");
    states_.push_back(tracker.state());
    references_.push_back(tracker.reference_rotation());
    rows_.push_back(row);
  }

  std::size_t frames() const { return states_.size(); }

  /// Replaces the rows of the recorded frames in `motion` (root position, roll/pitch/yaw, joint
  /// angles) by the smoothed poses.
  void smooth(io::MotionTable& motion) const {
    const std::vector<GaussianXd> smoothed = rts_smooth_random_walk(
        states_, process_noise_, [this](std::size_t k, Eigen::VectorXd& mean, Eigen::MatrixXd& covariance) {
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
          body::rpy_from_rotation(references_[k] * body::rotation_exp(m.segment<3>(3))).transpose();
      motion.values.row(row).tail(joints) = joints_.angles(m.tail(joints)).transpose();
    }
  }

 private:
  /// Step k+1's coordinates differ from step k's by the tracker's re-centring: the orientation error
  /// is about R_{k+1} instead of R_k, and a Theta that left [-pi/2, pi/2] was reflected to +-pi - Theta
  /// (the same angle, the sign of its covariance row and column flipped). Rewrites a Gaussian of
  /// step k+1 in step k's coordinates.
  void to_chart_of(std::size_t k, Eigen::VectorXd& mean, Eigen::MatrixXd& covariance) const {
    // R_{k+1} Exp(e) = R_k Exp(e') with Exp(e') = D Exp(e), D = R_k^T R_{k+1}: exact for the mean.
    // D is one frame's update, close to the identity, so the covariance is kept as it is (its
    // change is of the order of the angle of D times the error).
    const Eigen::Matrix3d d = references_[k].transpose() * references_[k + 1];
    mean.segment<3>(3) = body::rotation_log(d * body::rotation_exp(mean.segment<3>(3)));
    // Theta and pi - Theta (plus multiples of 2 pi) give the same angle: take the representative
    // nearest step k's filtered value.
    constexpr double kPi = 3.14159265358979323846;
    const Eigen::VectorXd& reference = states_[k].mean;
    for (Eigen::Index j = 6; j < mean.size(); ++j) {
      const auto nearest = [&](double value) {
        return value + 2 * kPi * std::round((reference(j) - value) / (2 * kPi));
      };
      const double direct = nearest(mean(j)), reflected = nearest(kPi - mean(j));
      if (std::abs(reflected - reference(j)) < std::abs(direct - reference(j))) {
        mean(j) = reflected;
        covariance.row(j) *= -1;
        covariance.col(j) *= -1;
      } else {
        mean(j) = direct;
      }
    }
  }

  body::BoundedJoints joints_;
  Eigen::MatrixXd process_noise_;
  std::vector<GaussianXd> states_;
  std::vector<Eigen::Matrix3d> references_;
  std::vector<Eigen::Index> rows_;
};

}  // namespace s2kf::track
