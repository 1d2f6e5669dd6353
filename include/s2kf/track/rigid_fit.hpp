/// @file
/// The rigid transform that best maps one point set onto another (least squares, Umeyama's method
/// without scale): how the tracker places the root on its first frame. Kept apart because Eigen's
/// SVD behind it is heavy to compile and the rest of the tracker does not need it.
#pragma once

#include <Eigen/Core>

namespace s2kf::track {

struct RigidTransform {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

/// R, t minimising sum |R from_i + t - to_i|^2 over the columns (3 x N each, N >= 3 not collinear
/// for a unique answer).
RigidTransform fit_rigid_transform(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to);

}  // namespace s2kf::track

#if !defined(S2KF_COMPILED) || defined(S2KF_COMPILING_LIBRARY)
#include <s2kf/track/rigid_fit_impl.hpp>
#endif
