/// @file
/// The per-frame gradient baseline (what MMM's converter and OpenSim's inverse kinematics do):
/// at every frame, minimise the sum of squared marker distances over the pose with the analytic
/// Jacobian (Levenberg-Marquardt), joint limits as bounds, warm-started from the previous frame.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
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

}  // namespace s2kf::track

#if !defined(S2KF_COMPILED)
#include <s2kf/track/gradient_baseline.hxx>
#endif
