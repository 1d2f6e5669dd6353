/// @file
/// The definitions of <s2kf/body/pose.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/body/pose.hpp>

namespace s2kf::body {

S2KF_INLINE Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, v / angle).toRotationMatrix();
}

S2KF_INLINE Eigen::Vector3d rotation_log(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd angle_axis(r);
  return angle_axis.angle() * angle_axis.axis();
}

}  // namespace s2kf::body
