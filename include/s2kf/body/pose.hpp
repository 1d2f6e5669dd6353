/// @file
/// A whole-body pose (root position, root roll/pitch/yaw, 40 joint angles) and the conversions
/// between roll/pitch/yaw, rotation vectors and rotation matrices.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/core/compilation_mode.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <string>
#include <vector>

namespace s2kf::body {

/// Rotation about one model axis by `angle` (rad).
inline Eigen::Matrix3d axis_rotation(Axis axis, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Eigen::Matrix3d r;
  switch (axis) {
    case Axis::x:
      r << 1, 0, 0, 0, c, -s, 0, s, c;
      break;
    case Axis::y:
      r << c, 0, s, 0, 1, 0, -s, 0, c;
      break;
    case Axis::z:
      r << c, -s, 0, s, c, 0, 0, 0, 1;
      break;
  }
  return r;
}

/// R = Rz(yaw) * Ry(pitch) * Rx(roll), rpy = (roll, pitch, yaw) in rad (the MMM convention).
inline Eigen::Matrix3d rotation_from_rpy(const Eigen::Vector3d& rpy) {
  const double cr = std::cos(rpy(0)), sr = std::sin(rpy(0));
  const double cp = std::cos(rpy(1)), sp = std::sin(rpy(1));
  const double cy = std::cos(rpy(2)), sy = std::sin(rpy(2));
  Eigen::Matrix3d r;
  r << cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,  //
      sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,   //
      -sp, cp * sr, cp * cr;
  return r;
}

/// The inverse of rotation_from_rpy with pitch in [-pi/2, pi/2], roll and yaw in (-pi, pi]. At
/// pitch = +-90 deg only roll -+ yaw is defined; then yaw = 0 and roll carries the whole rotation
/// about the vertical, so rotation_from_rpy(rpy_from_rotation(R)) == R still holds.
inline Eigen::Vector3d rpy_from_rotation(const Eigen::Matrix3d& r) {
  const double cos_pitch = std::hypot(r(0, 0), r(1, 0));
  const double pitch = std::atan2(-r(2, 0), cos_pitch);
  // Below 1e-6 the neglected terms of the closed form are O(cos_pitch^2) = 1e-12.
  if (cos_pitch < 1e-6) return {std::atan2(-r(2, 0) * r(0, 1), r(1, 1)), pitch, 0.0};
  return {std::atan2(r(2, 1), r(2, 2)), pitch, std::atan2(r(1, 0), r(0, 0))};
}

/// Exp of a rotation vector (axis times angle, rad): the rotation by |v| about v / |v|.
Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& v);

/// Log of a rotation matrix: the rotation vector with angle in [0, pi].
Eigen::Vector3d rotation_log(const Eigen::Matrix3d& r);

/// A whole-body pose: the root (pelvis) frame in the lab and the joint angles in state order. The
/// joint vector is sized by the model it belongs to (40 zeros by default, the MMM model's count);
/// forward kinematics refuses a pose whose size is not its model's joint count.
struct Pose {
  Eigen::Vector3d root_position = Eigen::Vector3d::Zero();      ///< mm, lab frame
  Eigen::Vector3d root_rpy = Eigen::Vector3d::Zero();           ///< roll, pitch, yaw (rad)
  Eigen::VectorXd joints = Eigen::VectorXd::Zero(kJointCount);  ///< rad

  Eigen::Matrix3d root_rotation() const { return rotation_from_rpy(root_rpy); }
};

/// The zero pose of a model: root at the origin, every joint angle 0.
inline Pose zero_pose(const BodyModel& model) {
  return Pose{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::VectorXd::Zero(model.joint_count())};
}

/// Number of values of a pose row before the joints: root position (3) and roll, pitch, yaw (3).
constexpr int kRootValues = 6;

/// A pose as one row of a motion table: root_x, root_y, root_z (mm), roll, pitch, yaw (rad), joints.
template <typename Row>
void write_pose_row(const Pose& pose, Row&& row) {
  row.template head<3>() = pose.root_position;
  row.template segment<3>(3) = pose.root_rpy;
  row.tail(row.size() - kRootValues) = pose.joints;
}

inline Eigen::VectorXd pose_row(const Pose& pose) {
  Eigen::VectorXd row(kRootValues + pose.joints.size());
  write_pose_row(pose, row);
  return row;
}

/// The pose of a motion-table row (the inverse of pose_row).
inline Pose pose_from_row(const Eigen::Ref<const Eigen::VectorXd>& row) {
  return Pose{row.head<3>(), row.segment<3>(3), row.tail(row.size() - kRootValues)};
}

/// The column names of a pose table (CSV) with these joints: frame, time (s), root_x, root_y,
/// root_z (mm), root_roll, root_pitch, root_yaw (rad, R = Rz Ry Rx), then the joint angles (rad).
inline std::vector<std::string> pose_column_names(const std::vector<std::string>& joint_names) {
  std::vector<std::string> names{"frame",  "time",      "root_x",     "root_y",
                                 "root_z", "root_roll", "root_pitch", "root_yaw"};
  names.insert(names.end(), joint_names.begin(), joint_names.end());
  return names;
}

}  // namespace s2kf::body

#if !defined(S2KF_COMPILED)
#include <s2kf/body/pose.hxx>
#endif
