/// @file
/// The per-frame gradient baseline (what MMM's converter and OpenSim's inverse kinematics do):
/// at every frame, minimise the sum of squared marker distances over the pose with the analytic
/// Jacobian (Levenberg-Marquardt), joint limits as bounds, warm-started from the previous frame.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/track/tracker.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <limits>
#include <vector>

namespace s2kf::track {

struct BaselineOptions {
  /// Gauss-Newton iterations per frame at most (the first frame, which starts from a rigid fit
  /// at the zero pose, gets first_frame_iterations).
  int max_iterations = 30;
  int first_frame_iterations = 200;
  /// Converged when no joint or orientation parameter moves by more than this in one step...
  double step_tolerance_rad = 1e-6;
  /// ...and the root moves by less than this.
  double step_tolerance_mm = 1e-4;
  /// Or when an accepted step lowers the cost (sum of squared distances) by less than this
  /// fraction: the pose then moves only along directions the markers barely see (the redundant
  /// neck and spine pairs), by amounts that change no marker distance measurably.
  double relative_tolerance = 1e-6;
  /// Levenberg-Marquardt damping (relative to the diagonal of J^T J) that a rejected Gauss-Newton
  /// step starts from; it shrinks tenfold with every accepted step and is dropped below 1e-9.
  double initial_damping = 1e-4;
  int min_markers_to_start = 8;
};

/// Same interface as Tracker: process() one frame, read the FrameEstimate. The root orientation is
/// updated through a rotation vector on the right of the current estimate (no roll-pitch-yaw
/// singularity). Joint limits are bounds: a joint on a limit whose gradient points outward is held
/// there for the step (an active set), every other step is projected onto the limits. Each frame
/// starts from the previous frame's pose and takes Gauss-Newton steps, falling back to
/// Levenberg-Marquardt damping only when a step does not lower the cost, until the step is below
/// the tolerances: a few iterations per frame.
class GradientBaseline {
 public:
  GradientBaseline(body::BodyModel model, body::MarkerMapping mapping, BaselineOptions options = {})
      : model_(std::move(model)), mapping_(std::move(mapping)), options_(options) {
    if (mapping_.point_of_marker.size() != static_cast<std::size_t>(model_.marker_count()))
      throw std::invalid_argument("the marker mapping does not fit the body model");
    if (options_.max_iterations < 1 || options_.first_frame_iterations < 1)
      throw std::invalid_argument("the baseline needs at least one iteration per frame");
    estimate_.marker_distance.resize(model_.marker_count());
    // The joints that move each model frame: walking parents from a frame reaches the root.
    chain_.resize(model_.frame_count());
    for (int f = 1; f < model_.frame_count(); ++f)
      for (int g = f; g > 0; g = model_.joints[g - 1].parent_frame) chain_[f].push_back(g);
  }

  const FrameEstimate& estimate() const { return estimate_; }
  /// Gauss-Newton/Levenberg-Marquardt iterations (linearisations) spent on the last frame.
  int last_iterations() const { return last_iterations_; }

  /// The next frame's fit starts from `pose` (and counts as initialised) instead of the previous
  /// frame's result: the true-subject reference starts every frame at the true pose.
  void start_from(const body::Pose& pose) {
    pose_ = pose;
    rotation_ = pose.root_rotation();
    initialised_ = true;
  }

  const FrameEstimate& process(const Eigen::Matrix3Xd& points,
                               const Eigen::Array<bool, Eigen::Dynamic, 1>& visible);

 private:
  void initialise(const Eigen::Matrix3Xd& points);

  /// Residuals (measured - predicted) of the observed markers and, when asked, the normal
  /// equations J^T J and J^T r over [position (3), rotation vector on the right (3), joints]. Each
  /// marker's Jacobian touches only the root and the joints of its chain, so J^T J is accumulated
  /// marker by marker on those columns. Returns the cost |r|^2.
  double linearise(const Eigen::Matrix3Xd& points, bool with_normal_equations);

  void apply(const Eigen::VectorXd& step);

  bool small(const Eigen::VectorXd& step) const {
    return step.head<3>().cwiseAbs().maxCoeff() <= options_.step_tolerance_mm &&
           step.tail(step.size() - 3).cwiseAbs().maxCoeff() <= options_.step_tolerance_rad;
  }

  void solve(const Eigen::Matrix3Xd& points, int max_iterations);

  body::BodyModel model_;
  body::MarkerMapping mapping_;
  BaselineOptions options_;
  body::Pose pose_;
  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();
  FrameEstimate estimate_;
  bool initialised_ = false;
  int last_iterations_ = 0;
  std::vector<std::vector<int>> chain_;  ///< per model frame: the frames of the joints that move it
  std::vector<int> markers_;             ///< model markers observed in the current frame
  Eigen::MatrixXd normal_;               ///< J^T J
  Eigen::VectorXd gradient_;             ///< J^T r
};

#if S2KF_DEFINE_HEAVY
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
#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::track
