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

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

S2KF_INLINE std::pair<MotionTable, MotionTable> motion_derivatives(const MotionTable& motion) {
  motion.check();
  MotionTable velocity, acceleration;
  for (MotionTable* table : {&velocity, &acceleration}) {
    table->joint_names = motion.joint_names;
    table->frame = motion.frame;
    table->time = motion.time;
    table->values.resize(motion.values.rows(), motion.values.cols());
  }
  Eigen::Index row = 0;
  MotionDerivativeStream stream([&](long, double, const Eigen::VectorXd& v, const Eigen::VectorXd& a) {
    velocity.values.row(row) = v.transpose();
    acceleration.values.row(row) = a.transpose();
    ++row;
  });
  for (Eigen::Index r = 0; r < motion.frames(); ++r)
    stream.push(motion.frame[static_cast<std::size_t>(r)], motion.time[static_cast<std::size_t>(r)],
                motion.values.row(r).transpose());
  stream.finish();
  return {velocity, acceleration};
}

S2KF_INLINE void MotionDerivativeStream::emit(const Row& row, const Row* before, const Row* after) const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd velocity = Eigen::VectorXd::Constant(row.values.size(), nan);
  Eigen::VectorXd acceleration = velocity;
  const bool has_before = row.tracked && before && before->tracked && before->time < row.time;
  const bool has_after = row.tracked && after && after->tracked && after->time > row.time;
  if (has_before && has_after) {
    const Eigen::VectorXd slope_before = difference(row.values, before->values) / (row.time - before->time);
    const Eigen::VectorXd slope_after = difference(after->values, row.values) / (after->time - row.time);
    velocity = difference(after->values, before->values) / (after->time - before->time);
    acceleration = 2 * (slope_after - slope_before) / (after->time - before->time);
  } else if (has_before) {
    velocity = difference(row.values, before->values) / (row.time - before->time);
  } else if (has_after) {
    velocity = difference(after->values, row.values) / (after->time - row.time);
  }
  sink_(row.frame, row.time, velocity, acceleration);
}

S2KF_INLINE void MotionDerivativeStream::push(long frame, double time, const MotionRowRef& values) {
  Row next{frame, time, values, is_tracked_row(values)};
  if (current_) emit(*current_, previous_ ? &*previous_ : nullptr, &next);
  previous_ = std::move(current_);
  current_ = std::move(next);
}

S2KF_INLINE void MotionDerivativeStream::finish() {
  if (current_) emit(*current_, previous_ ? &*previous_ : nullptr, nullptr);
  previous_.reset();
  current_.reset();
}

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::io
