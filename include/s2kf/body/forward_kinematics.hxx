/// @file
/// The definitions of <s2kf/body/forward_kinematics.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/body/forward_kinematics.hpp>

namespace s2kf::body {

S2KF_INLINE FrameTransforms joint_frames(const BodyModel& model, const Eigen::Vector3d& root_position,
                                         const Eigen::Matrix3d& root_rotation,
                                         const Eigen::Ref<const Eigen::VectorXd>& joint_angles) {
  detail::check_joint_count(model, joint_angles.size(), "joint_frames");
  FrameTransforms frames;
  frames.rotations.resize(model.frame_count());
  frames.origins.resize(model.frame_count());
  frames.rotations[0] = root_rotation;
  frames.origins[0] = root_position;
  for (int j = 0; j < model.joint_count(); ++j) {
    const Joint& joint = model.joints[j];
    const int p = joint.parent_frame;
    frames.origins[j + 1] = frames.origins[p] + frames.rotations[p] * joint.translation;
    frames.rotations[j + 1] = frames.rotations[p] * axis_rotation(joint.axis, joint_angles(j));
  }
  return frames;
}

S2KF_INLINE FrameTransforms joint_frames(const BodyModel& model, const Pose& pose) {
  return joint_frames(model, pose.root_position, pose.root_rotation(), pose.joints);
}

S2KF_INLINE Eigen::Matrix3Xd marker_positions(const BodyModel& model, const FrameTransforms& frames) {
  Eigen::Matrix3Xd positions(3, model.marker_count());
  for (int m = 0; m < model.marker_count(); ++m) {
    const Marker& marker = model.markers[m];
    positions.col(m) = frames.origins[marker.frame] + frames.rotations[marker.frame] * marker.offset;
  }
  return positions;
}

S2KF_INLINE Eigen::Matrix3Xd marker_positions(const BodyModel& model, const Eigen::Vector3d& root_position,
                                              const Eigen::Matrix3d& root_rotation,
                                              const Eigen::Ref<const Eigen::VectorXd>& joint_angles) {
  return marker_positions(model, joint_frames(model, root_position, root_rotation, joint_angles));
}

S2KF_INLINE Eigen::Matrix3Xd marker_positions(const BodyModel& model, const Pose& pose) {
  return marker_positions(model, joint_frames(model, pose));
}

S2KF_INLINE Eigen::MatrixXd marker_jacobian(const BodyModel& model, const Eigen::Vector3d& root_position,
                                            const Eigen::Vector3d& root_rpy,
                                            const Eigen::Ref<const Eigen::VectorXd>& joint_angles) {
  const FrameTransforms frames =
      joint_frames(model, root_position, rotation_from_rpy(root_rpy), joint_angles);
  const Eigen::Matrix3Xd positions = marker_positions(model, frames);
  const Eigen::Matrix3d yaw = axis_rotation(Axis::z, root_rpy(2));
  const Eigen::Matrix3d yaw_pitch = yaw * axis_rotation(Axis::y, root_rpy(1));
  const Eigen::Vector3d root_axes[3] = {yaw_pitch.col(0), yaw.col(1), Eigen::Vector3d::UnitZ()};
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(3 * model.marker_count(), 6 + model.joint_count());
  for (int m = 0; m < model.marker_count(); ++m) {
    const Eigen::Vector3d p = positions.col(m);
    // Fixed-size blocks: GCC 12 with AVX-512 misreads 3-vectors copied into dynamic blocks (-Warray-bounds).
    jacobian.block<3, 3>(3 * m, 0).setIdentity();
    const Eigen::Vector3d from_root = p - root_position;
    for (int k = 0; k < 3; ++k) jacobian.block<3, 1>(3 * m, 3 + k) = root_axes[k].cross(from_root);
    for (int f = model.markers[m].frame; f > 0; f = model.joints[f - 1].parent_frame) {
      const Joint& joint = model.joints[f - 1];
      const Eigen::Vector3d axis = frames.rotations[f].col(static_cast<int>(joint.axis));
      jacobian.block<3, 1>(3 * m, 6 + f - 1) = axis.cross(p - frames.origins[f]);
    }
  }
  return jacobian;
}

S2KF_INLINE Eigen::MatrixXd marker_jacobian(const BodyModel& model, const Pose& pose) {
  return marker_jacobian(model, pose.root_position, pose.root_rpy, pose.joints);
}

S2KF_INLINE void marker_positions_batch(const BodyModel& model,
                                        const Eigen::Ref<const Eigen::MatrixXd>& root_positions,
                                        const Eigen::Ref<const Eigen::MatrixXd>& root_rotations,
                                        const Eigen::Ref<const Eigen::MatrixXd>& joint_angles,
                                        ForwardKinematicsWorkspace& ws, Eigen::Ref<Eigen::MatrixXd> markers) {
  const Eigen::Index count = root_positions.cols();
  if (root_positions.rows() != 3 || root_rotations.rows() != 9 || root_rotations.cols() != count ||
      joint_angles.rows() != model.joint_count() || joint_angles.cols() != count ||
      markers.rows() != 3 * model.marker_count() || markers.cols() != count)
    throw DimensionError("marker_positions_batch: expected 3 x L positions, 9 x L rotations, " +
                         std::to_string(model.joint_count()) + " x L joint angles and " +
                         std::to_string(3 * model.marker_count()) + " x L markers");
  ws.prepare(model, model.marker_count());
  constexpr Eigen::Index S = ForwardKinematicsWorkspace::kStride;
  const Eigen::Index B = ForwardKinematicsWorkspace::block_size(count);
  for (Eigen::Index start = 0; start < count; start += B) {
    const Eigen::Index n = std::min(B, count - start);
    for (Eigen::Index i = 0; i < n; ++i) {
      for (int r = 0; r < 3; ++r) ws.root_position[r * S + i] = root_positions(r, start + i);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          ws.root_rotation[(3 * c + r) * S + i] = root_rotations(3 * r + c, start + i);
    }
    // Joint angles arrive one pose per column; stage them one joint per array, then take sin and cos.
    for (Eigen::Index i = 0; i < n; ++i)
      for (int j = 0; j < model.joint_count(); ++j) ws.angles[j * S + i] = joint_angles(j, start + i);
    for (int j = 0; j < model.joint_count(); ++j)
      vector_sincos(ws.array(ws.angles, j), ws.array(ws.sin_q, j), ws.array(ws.cos_q, j), n);
    forward_kinematics_block(model, ws.all_markers, ws, n);
    copy_markers_out(ws, n, markers.middleCols(start, n));
  }
}

}  // namespace s2kf::body
