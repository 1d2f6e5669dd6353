/// @file
/// The rigid transform that best maps one point set onto another (least squares, Umeyama's method
/// without scale): how the tracker places the root on its first frame.
#pragma once

#include <s2kf/core/compilation_mode.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace s2kf::geometry {

struct RigidTransform {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

/// R, t minimising sum |R from_i + t - to_i|^2 over the columns (3 x N each; N >= 3 points not on
/// one line for a unique answer).
RigidTransform fit_rigid_transform(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to);

}  // namespace s2kf::geometry

#if !defined(S2KF_COMPILED)
#include <s2kf/geometry/rigid_fit.hxx>
#endif
