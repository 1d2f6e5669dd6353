/// @file
/// The definitions of <s2kf/geometry/rigid_fit.hpp>: inline where the library is used header-only, compiled
/// once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/geometry/rigid_fit.hpp>

namespace s2kf::geometry {
S2KF_INLINE RigidTransform fit_rigid_transform(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to) {
  const Eigen::Matrix4d fit = Eigen::umeyama(from, to, false);
  RigidTransform transform;
  transform.rotation = fit.topLeftCorner<3, 3>();
  transform.translation = fit.topRightCorner<3, 1>();
  return transform;
}
}  // namespace s2kf::geometry
