/// @file
/// The definitions of <s2kf/core/marginal_update.hpp>: inline where the library is used header-only, compiled
/// once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/core/marginal_update.hpp>

namespace s2kf {
S2KF_INLINE bool MarginalUpdate::apply(GaussianXd& joint, const GaussianXd& head_posterior) {
  const Eigen::Index n = head_posterior.dimension(), d = joint.dimension();
  if (n > d || head_posterior.covariance.rows() != n || joint.covariance.rows() != d)
    throw DimensionError("MarginalUpdate: the head (" + std::to_string(n) +
                         ") does not fit the joint state (" + std::to_string(d) + ")");
  const Eigen::Index m = d - n;
  factor_.compute(joint.covariance.topLeftCorner(n, n));
  if (factor_.info() != Eigen::Success) return false;
  gain_.noalias() = factor_.solve(joint.covariance.topRightCorner(n, m)).transpose();  // C_vp C_pp^-1
  joint.mean.tail(m).noalias() += gain_ * (head_posterior.mean - joint.mean.head(n));
  shrink_ = joint.covariance.topLeftCorner(n, n) - head_posterior.covariance;
  product_.noalias() = gain_ * shrink_;
  joint.covariance.bottomRightCorner(m, m).noalias() -= product_ * gain_.transpose();
  joint.covariance.bottomLeftCorner(m, n).noalias() = gain_ * head_posterior.covariance;
  joint.covariance.topRightCorner(n, m) = joint.covariance.bottomLeftCorner(m, n).transpose();
  joint.covariance.topLeftCorner(n, n) = head_posterior.covariance;
  joint.mean.head(n) = head_posterior.mean;
  return true;
}
}  // namespace s2kf
