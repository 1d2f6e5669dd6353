/// @file
/// The bounded joint parameterisation of the tracker's state: every real parameter Theta maps to an
/// angle inside the joint's limits, theta = (u - l)/2 sin(Theta) + (u + l)/2.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/error.hpp>
#include <s2kf/core/instruction_set.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace s2kf::body {

/// Limits of all joints and the map between parameters Theta and angles theta, vectorised over the
/// joints. Invariants: lower <= upper elementwise. A joint with upper == lower is fixed: its angle
/// is lower whatever Theta is (NaN included) and its inverse parameter is 0.
///
/// Non-finite parameters: sin(NaN) and sin(+-inf) are NaN, so a movable joint's angle is NaN. That
/// is deliberate: the filter then reports non_finite_model_output instead of silently tracking a
/// broken state. Every finite Theta (1e6, -1e9, ...) gives an angle within [lower, upper].
///
/// The map itself, from sin(Theta): (u - l)/2 sin(Theta) + (u + l)/2, clamped to [l, u] once more so
/// rounding never leaves the range (NaN passes through). Every user of the map calls this one
/// function (the batched measurement model with sines it computed in bulk).
template <typename Scalar>
S2KF_ALWAYS_INLINE Scalar bounded_angle_from_sine(Scalar sine, Scalar lower, Scalar upper) {
  if (upper == lower) return lower;
  const Scalar half(0.5);
  const Scalar v = half * (upper - lower) * sine + half * (upper + lower);
  return v < lower ? lower : (v > upper ? upper : v);
}

struct BoundedJoints {
  Eigen::ArrayXd lower, upper;  ///< rad

  BoundedJoints() = default;
  BoundedJoints(Eigen::ArrayXd lower_limits, Eigen::ArrayXd upper_limits)
      : lower(std::move(lower_limits)), upper(std::move(upper_limits)) {
    if (lower.size() != upper.size())
      throw DimensionError("BoundedJoints: lower and upper limits differ in size");
    if (!(lower <= upper).all())
      throw std::invalid_argument("BoundedJoints: a lower limit is above its upper limit");
  }
  explicit BoundedJoints(const BodyModel& model)
      : BoundedJoints(model.lower_limits(), model.upper_limits()) {}

  Eigen::Index size() const { return lower.size(); }
  Eigen::ArrayXd half_range() const { return 0.5 * (upper - lower); }
  Eigen::ArrayXd middle() const { return 0.5 * (upper + lower); }

  /// theta of joint j for its parameter Theta (bounded_angle_from_sine).
  double angle(Eigen::Index j, double parameter) const {
    return bounded_angle_from_sine(std::sin(parameter), lower(j), upper(j));
  }

  /// theta for every joint.
  Eigen::VectorXd angles(const Eigen::Ref<const Eigen::VectorXd>& parameters) const;

  /// The parameter on the principal branch, Theta in [-pi/2, pi/2]: asin of the normalised angle,
  /// clamped to [-1, 1] so angles at or beyond a limit map to +-pi/2. Fixed joints give 0.
  Eigen::VectorXd parameters(const Eigen::Ref<const Eigen::VectorXd>& angles) const;

  /// d theta / d Theta = (u - l)/2 cos(Theta) per joint (0 for fixed joints).
  Eigen::VectorXd derivative(const Eigen::Ref<const Eigen::VectorXd>& parameters) const;

  /// Angles within limits? (NaN is not.)
  bool within_limits(const Eigen::Ref<const Eigen::VectorXd>& angles) const {
    check(angles.size(), "within_limits");
    return (angles.array() >= lower && angles.array() <= upper).all();
  }

 private:
  void check(Eigen::Index n, const char* where) const {
    if (n != size())
      throw DimensionError(std::string("BoundedJoints::") + where + ": " + std::to_string(n) +
                           " values for " + std::to_string(size()) + " joints");
  }
};

}  // namespace s2kf::body

#if !defined(S2KF_COMPILED)
#include <s2kf/body/bounded_joints.hxx>
#endif
