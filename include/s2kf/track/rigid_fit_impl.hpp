/// @file
/// Definition of fit_rigid_transform (rigid_fit.hpp). Header-only builds include it through
/// rigid_fit.hpp; with S2KF_COMPILED it is compiled once into the s2kf_compiled library.
#pragma once

#include <s2kf/core/compiled.hpp>
#include <s2kf/track/rigid_fit.hpp>

#include <Eigen/Geometry>

namespace s2kf::track {

S2KF_INLINE RigidTransform fit_rigid_transform(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to) {
  const Eigen::Matrix4d fit = Eigen::umeyama(from, to, false);
  RigidTransform transform;
  transform.rotation = fit.topLeftCorner<3, 3>();
  transform.translation = fit.topRightCorner<3, 1>();
  return transform;
}

}  // namespace s2kf::track
