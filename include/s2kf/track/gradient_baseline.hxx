/// @file
/// The definitions of <s2kf/track/gradient_baseline.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/track/gradient_baseline.hpp>

namespace s2kf::track {
S2KF_INLINE const FrameEstimate& GradientBaseline::process(
    const Eigen::Matrix3Xd& points, const Eigen::Array<bool, Eigen::Dynamic, 1>& visible) {
  const auto start = std::chrono::steady_clock::now();
  if (points.cols() != visible.size())
    throw std::invalid_argument("process: one visibility flag per recording point is needed");
  markers_.clear();  // model markers observed this frame
  for (int m = 0; m < model_.marker_count(); ++m) {
    const int p = mapping_.point_of_marker[m];
    if (p >= 0 && p < points.cols() && visible(p) && points.col(p).allFinite()) markers_.push_back(m);
  }
  estimate_.visible_markers = static_cast<int>(markers_.size());
  last_iterations_ = 0;
  bool first = false;
  if (!initialised_ && static_cast<int>(markers_.size()) >= options_.min_markers_to_start) {
    initialise(points);
    first = true;
  }
  if (initialised_ && !markers_.empty())
    solve(points, first ? options_.first_frame_iterations : options_.max_iterations);
  estimate_.tracked = initialised_;
  estimate_.status = initialised_ && !markers_.empty() ? FilterStatus::ok : FilterStatus::nothing_observed;
  estimate_.marker_distance.setConstant(std::numeric_limits<double>::quiet_NaN());
  estimate_.mean_marker_distance = std::numeric_limits<double>::quiet_NaN();
  if (initialised_) {
    estimate_.pose = pose_;
    estimate_.root_rotation = rotation_;
    estimate_.predicted_markers =
        body::marker_positions(model_, pose_.root_position, rotation_, pose_.joints);
    double sum = 0;
    for (int m : markers_) {
      estimate_.marker_distance(m) =
          (points.col(mapping_.point_of_marker[m]) - estimate_.predicted_markers.col(m)).norm();
      sum += estimate_.marker_distance(m);
    }
    if (!markers_.empty()) estimate_.mean_marker_distance = sum / static_cast<double>(markers_.size());
  }
  estimate_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return estimate_;
}

S2KF_INLINE void GradientBaseline::initialise(const Eigen::Matrix3Xd& points) {
  pose_ = body::zero_pose(model_);
  const Eigen::Matrix3Xd zero = body::marker_positions(model_, pose_);
  Eigen::Matrix3Xd measured(3, markers_.size()), reference(3, markers_.size());
  for (std::size_t k = 0; k < markers_.size(); ++k) {
    measured.col(k) = points.col(mapping_.point_of_marker[markers_[k]]);
    reference.col(k) = zero.col(markers_[k]);
  }
  const Eigen::Matrix4d fit = Eigen::umeyama(reference, measured, false);
  rotation_ = fit.topLeftCorner<3, 3>();
  pose_.root_position = fit.topRightCorner<3, 1>();
  pose_.root_rpy = body::rpy_from_rotation(rotation_);
  initialised_ = true;
}

S2KF_INLINE double GradientBaseline::linearise(const Eigen::Matrix3Xd& points, bool with_normal_equations) {
  const body::FrameTransforms frames =
      body::joint_frames(model_, pose_.root_position, rotation_, pose_.joints);
  const int n = 6 + model_.joint_count();
  if (with_normal_equations) {
    normal_.setZero(n, n);
    gradient_.setZero(n);
  }
  double cost = 0;
  std::vector<int> columns;
  Eigen::Matrix<double, 3, Eigen::Dynamic> block;
  for (int m : markers_) {
    const body::Marker& marker = model_.markers[m];
    const Eigen::Vector3d p = frames.origins[marker.frame] + frames.rotations[marker.frame] * marker.offset;
    const Eigen::Vector3d r = points.col(mapping_.point_of_marker[m]) - p;
    cost += r.squaredNorm();
    if (!with_normal_equations) continue;
    const std::vector<int>& chain = chain_[marker.frame];
    const int width = 6 + static_cast<int>(chain.size());
    block.resize(3, width);
    columns.resize(width);
    const Eigen::Vector3d arm = p - pose_.root_position;
    Eigen::Matrix3d skew;
    skew << 0, -arm.z(), arm.y(), arm.z(), 0, -arm.x(), -arm.y(), arm.x(), 0;
    block.leftCols<3>().setIdentity();
    block.middleCols<3>(3) = -skew * rotation_;  // d p / d omega for R <- R Exp(omega)
    for (int c = 0; c < 6; ++c) columns[c] = c;
    for (std::size_t k = 0; k < chain.size(); ++k) {
      const int f = chain[k];
      const body::Joint& joint = model_.joints[f - 1];
      const Eigen::Vector3d axis = frames.rotations[f].col(static_cast<int>(joint.axis));
      block.col(6 + static_cast<Eigen::Index>(k)) = axis.cross(p - frames.origins[f]);
      columns[6 + k] = 6 + f - 1;
    }
    const Eigen::MatrixXd local = block.transpose() * block;
    const Eigen::VectorXd local_gradient = block.transpose() * r;
    for (int a = 0; a < width; ++a) {
      gradient_(columns[a]) += local_gradient(a);
      for (int b = 0; b < width; ++b) normal_(columns[a], columns[b]) += local(a, b);
    }
  }
  return cost;
}

S2KF_INLINE void GradientBaseline::apply(const Eigen::VectorXd& step) {
  pose_.root_position += step.head<3>();
  const Eigen::Vector3d omega = step.segment<3>(3);
  if (omega.norm() > 0)
    rotation_ = rotation_ * Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix();
  pose_.root_rpy = body::rpy_from_rotation(rotation_);
  for (int j = 0; j < model_.joint_count(); ++j)
    pose_.joints(j) =
        std::clamp(pose_.joints(j) + step(6 + j), model_.joints[j].lower, model_.joints[j].upper);
}

S2KF_INLINE void GradientBaseline::solve(const Eigen::Matrix3Xd& points, int max_iterations) {
  double cost = linearise(points, true);
  double damping = 0;  // Gauss-Newton until a step fails to lower the cost
  Eigen::VectorXd step;
  Eigen::MatrixXd damped;
  for (int it = 0; it < max_iterations; ++it) {
    ++last_iterations_;
    // Active set: a joint on a limit that the gradient pushes further out stays there.
    for (int j = 0; j < model_.joint_count(); ++j) {
      const double g = gradient_(6 + j), q = pose_.joints(j);
      if ((q <= model_.joints[j].lower && g < 0) || (q >= model_.joints[j].upper && g > 0)) {
        normal_.row(6 + j).setZero();
        normal_.col(6 + j).setZero();
        normal_(6 + j, 6 + j) = 1;
        gradient_(6 + j) = 0;
      }
    }
    const body::Pose saved_pose = pose_;
    const Eigen::Matrix3d saved_rotation = rotation_;
    bool accepted = false;
    for (int attempt = 0; attempt < 16 && !accepted; ++attempt) {
      // A floor of 1e-9 relative damping keeps the exactly redundant directions (BP/BT, BLN/BUN
      // axial rotations) solvable without changing the Gauss-Newton step anywhere else.
      damped = normal_;
      damped.diagonal() += (std::max(damping, 1e-9) * (normal_.diagonal().array() + 1e-6)).matrix();
      step = damped.ldlt().solve(gradient_);
      if (!step.allFinite()) step.setZero();
      if (small(step)) {  // converged: take the last tiny step unless it makes matters worse
        apply(step);
        if (linearise(points, false) > cost) pose_ = saved_pose, rotation_ = saved_rotation;
        return;
      }
      apply(step);
      const double trial = linearise(points, false);
      if (trial <= cost) {
        accepted = true;
        if (cost - trial <= options_.relative_tolerance * cost) return;
        cost = trial;
        damping = damping / 10 < 1e-9 ? 0 : damping / 10;
      } else {
        pose_ = saved_pose;
        rotation_ = saved_rotation;
        damping = damping == 0 ? options_.initial_damping : damping * 10;
      }
    }
    if (!accepted) return;  // no step lowers the cost: at the minimum to machine precision
    if (it + 1 < max_iterations) cost = linearise(points, true);
  }
}
}  // namespace s2kf::track
