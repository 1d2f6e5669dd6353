/// @file
/// The definitions of <s2kf/io/motion_derivatives.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/io/motion_derivatives.hpp>

namespace s2kf::io {

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

}  // namespace s2kf::io
