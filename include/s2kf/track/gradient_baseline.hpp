/// @file
/// The per-frame gradient baseline (what MMM's converter and OpenSim's inverse kinematics do):
/// at every frame, minimise the sum of squared marker distances over the pose with the analytic
/// Jacobian (Levenberg-Marquardt), joint limits as bounds, warm-started from the previous frame.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/track/marker_mapping.hpp>
#include <s2kf/track/tracker.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <limits>
#include <vector>

namespace s2kf::track {

struct BaselineOptions {
  int max_iterations = 100;         ///< Levenberg-Marquardt iterations per frame at most
  double relative_tolerance = 1e-10;  ///< stop when the cost falls by less than this fraction
  double initial_damping = 1e-3;
  int min_markers_to_start = 8;
};

/// Same interface as Tracker: process() one frame, read the FrameEstimate. The root orientation is
/// updated through a rotation vector on the right of the current estimate (no roll-pitch-yaw
/// singularity), joint angles are projected onto their limits after every step.
class GradientBaseline {
 public:
  GradientBaseline(body::BodyModel model, MarkerMapping mapping, BaselineOptions options = {})
      : model_(std::move(model)), mapping_(std::move(mapping)), options_(options) {
    if (mapping_.point_of_marker.size() != static_cast<std::size_t>(model_.marker_count()))
      throw std::invalid_argument("the marker mapping does not fit the body model");
    estimate_.marker_distance.resize(model_.marker_count());
  }

  const FrameEstimate& estimate() const { return estimate_; }
  int last_iterations() const { return last_iterations_; }

  const FrameEstimate& process(const Eigen::Matrix3Xd& points, const Eigen::Array<bool, Eigen::Dynamic, 1>& visible) {
    const auto start = std::chrono::steady_clock::now();
    if (points.cols() != visible.size())
      throw std::invalid_argument("process: one visibility flag per recording point is needed");
    std::vector<int> markers;  // model markers observed this frame
    for (int m = 0; m < model_.marker_count(); ++m) {
      const int p = mapping_.point_of_marker[m];
      if (p >= 0 && p < points.cols() && visible(p) && points.col(p).allFinite()) markers.push_back(m);
    }
    estimate_.visible_markers = static_cast<int>(markers.size());
    if (!initialised_ && static_cast<int>(markers.size()) >= options_.min_markers_to_start) initialise(points, markers);
    if (initialised_ && !markers.empty()) solve(points, markers);
    estimate_.tracked = initialised_;
    estimate_.status = initialised_ && !markers.empty() ? FilterStatus::ok : FilterStatus::nothing_observed;
    estimate_.marker_distance.setConstant(std::numeric_limits<double>::quiet_NaN());
    estimate_.mean_marker_distance = std::numeric_limits<double>::quiet_NaN();
    if (initialised_) {
      estimate_.pose = pose_;
      estimate_.root_rotation = rotation_;
      estimate_.predicted_markers = body::marker_positions(model_, pose_);
      double sum = 0;
      for (int m : markers) {
        estimate_.marker_distance(m) = (points.col(mapping_.point_of_marker[m]) - estimate_.predicted_markers.col(m)).norm();
        sum += estimate_.marker_distance(m);
      }
      if (!markers.empty()) estimate_.mean_marker_distance = sum / static_cast<double>(markers.size());
    }
    estimate_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return estimate_;
  }

 private:
  void initialise(const Eigen::Matrix3Xd& points, const std::vector<int>& markers) {
    pose_ = body::Pose{};
    const Eigen::Matrix3Xd zero = body::marker_positions(model_, pose_);
    Eigen::Matrix3Xd measured(3, markers.size()), reference(3, markers.size());
    for (std::size_t k = 0; k < markers.size(); ++k) {
      measured.col(k) = points.col(mapping_.point_of_marker[markers[k]]);
      reference.col(k) = zero.col(markers[k]);
    }
    const Eigen::Matrix4d fit = Eigen::umeyama(reference, measured, false);
    rotation_ = fit.topLeftCorner<3, 3>();
    pose_.root_position = fit.topRightCorner<3, 1>();
    pose_.root_rpy = body::rpy_from_rotation(rotation_);
    initialised_ = true;
  }

  /// Residuals and Jacobian over [position (3), rotation vector on the right (3), joints].
  double linearise(const Eigen::Matrix3Xd& points, const std::vector<int>& markers, Eigen::VectorXd& residual,
                   Eigen::MatrixXd* jacobian) const {
    const Eigen::Matrix3Xd predicted = body::marker_positions(model_, pose_);
    const Eigen::Index rows = 3 * static_cast<Eigen::Index>(markers.size());
    residual.resize(rows);
    for (std::size_t k = 0; k < markers.size(); ++k)
      residual.segment<3>(3 * k) = points.col(mapping_.point_of_marker[markers[k]]) - predicted.col(markers[k]);
    if (jacobian) {
      const Eigen::MatrixXd full = body::marker_jacobian(model_, pose_);  // 3M x (6 + joints), rpy columns 3..5
      const int nj = model_.joint_count();
      jacobian->resize(rows, 6 + nj);
      for (std::size_t k = 0; k < markers.size(); ++k) {
        const int m = markers[k];
        const Eigen::Vector3d arm = predicted.col(m) - pose_.root_position;
        Eigen::Matrix3d skew;
        skew << 0, -arm.z(), arm.y(), arm.z(), 0, -arm.x(), -arm.y(), arm.x(), 0;
        jacobian->block(3 * k, 0, 3, 3).setIdentity();
        jacobian->block(3 * k, 3, 3, 3) = -skew * rotation_;  // d p / d omega for R <- R Exp(omega)
        jacobian->block(3 * k, 6, 3, nj) = full.block(3 * m, 6, 3, nj);
      }
    }
    return residual.squaredNorm();
  }

  void apply(const Eigen::VectorXd& step) {
    pose_.root_position += step.head<3>();
    const Eigen::Vector3d omega = step.segment<3>(3);
    if (omega.norm() > 0) rotation_ = rotation_ * Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix();
    pose_.root_rpy = body::rpy_from_rotation(rotation_);
    for (int j = 0; j < model_.joint_count(); ++j)
      pose_.joints(j) = std::clamp(pose_.joints(j) + step(6 + j), model_.joints[j].lower, model_.joints[j].upper);
  }

  void solve(const Eigen::Matrix3Xd& points, const std::vector<int>& markers) {
    Eigen::VectorXd residual, trial_residual;
    Eigen::MatrixXd jacobian;
    double cost = linearise(points, markers, residual, &jacobian);
    double damping = options_.initial_damping;
    last_iterations_ = 0;
    for (int it = 0; it < options_.max_iterations; ++it) {
      ++last_iterations_;
      Eigen::MatrixXd normal = jacobian.transpose() * jacobian;
      const Eigen::VectorXd gradient = jacobian.transpose() * residual;
      bool improved = false;
      const body::Pose saved_pose = pose_;
      const Eigen::Matrix3d saved_rotation = rotation_;
      for (int attempt = 0; attempt < 12 && !improved; ++attempt) {
        Eigen::MatrixXd damped = normal;
        damped.diagonal() += damping * (normal.diagonal().array() + 1e-9).matrix();
        const Eigen::VectorXd step = damped.ldlt().solve(gradient);
        apply(step);
        const double trial = linearise(points, markers, trial_residual, nullptr);
        if (trial < cost) {
          improved = true;
          const double decrease = (cost - trial) / std::max(cost, 1e-300);
          cost = trial;
          damping = std::max(damping / 10, 1e-12);
          if (decrease < options_.relative_tolerance) return;
          cost = linearise(points, markers, residual, &jacobian);
        } else {
          pose_ = saved_pose;
          rotation_ = saved_rotation;
          damping *= 10;
        }
      }
      if (!improved) return;  // no step lowers the cost: converged to machine precision
    }
  }

  body::BodyModel model_;
  MarkerMapping mapping_;
  BaselineOptions options_;
  body::Pose pose_;
  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();
  FrameEstimate estimate_;
  bool initialised_ = false;
  int last_iterations_ = 0;
};

}  // namespace s2kf::track
