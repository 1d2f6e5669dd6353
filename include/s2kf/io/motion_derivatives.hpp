/// @file
/// Velocities and accelerations of a motion (root position, root roll/pitch/yaw, joint angles) by
/// finite differences of its rows, frame by frame with a three-row window, for inverse dynamics.
#pragma once

#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/motion_files.hpp>

#include <Eigen/Core>

#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <utility>

namespace s2kf::io {

/// Turns a stream of motion rows into velocity and acceleration rows of the same columns (mm/s and
/// rad/s; mm/s^2 and rad/s^2), one frame behind: row i is emitted once row i + 1 (or finish()) arrived.
///
/// Frame i with tracked neighbours on both sides: the three-point formulas on the (possibly uneven)
/// times t-, t, t+: v = (x+ - x-) / (t+ - t-) and a = 2 ((x+ - x)/(t+ - t) - (x - x-)/(t - t-)) / (t+ - t-),
/// exact for a parabola. With one tracked neighbour: the one-sided difference for v, NaN for a. An
/// untracked frame, or one without tracked neighbours, is NaN. Differences of the root's roll and
/// yaw are taken modulo 2 pi (the angles jump by 2 pi at +-180 deg; the motion does not).
class MotionDerivativeStream {
 public:
  using Sink = std::function<void(long frame, double time, const Eigen::VectorXd& velocity,
                                  const Eigen::VectorXd& acceleration)>;

  explicit MotionDerivativeStream(Sink sink) : sink_(std::move(sink)) {}

  void push(long frame, double time, const MotionRowRef& values);

  /// Emits the last row.
  void finish();

 private:
  struct Row {
    long frame;
    double time;
    Eigen::VectorXd values;
    bool tracked;
  };

  /// b - a, with the root's angles (columns 3..5) brought into (-pi, pi].
  static Eigen::VectorXd difference(const Eigen::VectorXd& b, const Eigen::VectorXd& a) {
    Eigen::VectorXd d = b - a;
    const double two_pi = 6.283185307179586477;
    for (int c = 3; c < 6 && c < d.size(); ++c) d(c) -= two_pi * std::round(d(c) / two_pi);
    return d;
  }

  void emit(const Row& row, const Row* before, const Row* after) const;

  Sink sink_;
  std::optional<Row> previous_, current_;
};

/// Velocities and accelerations of a whole motion (MotionDerivativeStream's rules).
std::pair<MotionTable, MotionTable> motion_derivatives(const MotionTable& motion);

}  // namespace s2kf::io

#if !defined(S2KF_COMPILED)
#include <s2kf/io/motion_derivatives.hxx>
#endif
