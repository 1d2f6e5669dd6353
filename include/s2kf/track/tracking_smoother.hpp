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

}  // namespace s2kf::track

#if !defined(S2KF_COMPILED)
#include <s2kf/track/tracking_smoother.hxx>
#endif
