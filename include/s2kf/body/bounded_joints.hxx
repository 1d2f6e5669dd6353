/// @file
/// The definitions of <s2kf/body/bounded_joints.hpp>: inline where the library is used header-only, compiled
/// once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/body/bounded_joints.hpp>

namespace s2kf::body {

S2KF_INLINE Eigen::VectorXd BoundedJoints::angles(const Eigen::Ref<const Eigen::VectorXd>& parameters) const {
  check(parameters.size(), "angles");
  Eigen::VectorXd theta(size());
  for (Eigen::Index j = 0; j < size(); ++j) theta(j) = angle(j, parameters(j));
  return theta;
}

S2KF_INLINE Eigen::VectorXd BoundedJoints::parameters(const Eigen::Ref<const Eigen::VectorXd>& angles) const {
  check(angles.size(), "parameters");
  Eigen::VectorXd result(size());
  for (Eigen::Index j = 0; j < size(); ++j) {
    const double half = 0.5 * (upper(j) - lower(j));
    if (half == 0) {
      result(j) = 0;
      continue;
    }
    const double normalised = (angles(j) - 0.5 * (upper(j) + lower(j))) / half;
    result(j) = std::asin(std::clamp(normalised, -1.0, 1.0));
  }
  return result;
}

S2KF_INLINE Eigen::VectorXd BoundedJoints::derivative(
    const Eigen::Ref<const Eigen::VectorXd>& parameters) const {
  check(parameters.size(), "derivative");
  Eigen::VectorXd result(size());
  for (Eigen::Index j = 0; j < size(); ++j) {
    const double half = 0.5 * (upper(j) - lower(j));
    result(j) = half == 0 ? 0.0 : half * std::cos(parameters(j));
  }
  return result;
}

}  // namespace s2kf::body
