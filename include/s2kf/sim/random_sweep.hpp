/// @file
/// A seeded random smooth motion that drives every joint from near one limit to near the other,
/// for testing a tracker over the whole joint space rather than on one choreography.
#pragma once

#include <s2kf/sim/keyframe_motion.hpp>
#include <s2kf/sim/random.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>

namespace s2kf::sim {

struct RandomSweepOptions {
  double duration_s = 12.0;          ///< the motion lasts this long
  double keyframe_interval_s = 1.0;  ///< one random keyframe this often (sets the speed)
  /// Each keyframe puts a joint within this fraction of its range from one of its limits
  /// (but no closer than a tenth of that), alternating sides so that every joint sweeps.
  double limit_band = 0.2;
  double root_wander_mm = 150.0;  ///< horizontal root excursion at the reference height
  double root_tilt_rad = 0.25;    ///< roll and pitch excursion
  double root_turn_rad = 1.0;     ///< yaw excursion
};

/// The random sweep for `seed`. Keyframe 0 is the zero pose standing at the origin (root at
/// z = 530 mm, hip height at the reference height); afterwards each joint's keyframes change side
/// (near the lower / near the upper limit) with probability 0.7 and at least every third
/// keyframe, so over a few seconds every joint travels through at least 1 - 2 limit_band of its
/// range. Between keyframes the monotone cubic keeps it within the limits.
inline KeyframeMotion random_sweep_motion(std::uint64_t seed, const Eigen::VectorXd& lower,
                                          const Eigen::VectorXd& upper,
                                          const RandomSweepOptions& options = {}) {
  if (lower.size() != upper.size() || (lower.array() > upper.array()).any())
    throw std::invalid_argument("random sweep: the joint limits must be pairs with lower <= upper");
  if (!(options.duration_s > 0.0) || !(options.keyframe_interval_s > 0.0) ||
      options.duration_s / options.keyframe_interval_s > 1e6)
    throw std::invalid_argument("random sweep: duration and keyframe interval must be positive");
  if (!(options.limit_band > 0.0 && options.limit_band <= 0.5))
    throw std::invalid_argument("random sweep: the limit band must lie in (0, 0.5]");
  std::mt19937_64 rng(derive_seed(seed, 0x5377656570ULL));
  const auto count =
      static_cast<Eigen::Index>(std::ceil(options.duration_s / options.keyframe_interval_s - 1e-9)) + 1;
  const Eigen::Index joints = lower.size();

  KeyframeMotion motion;
  motion.name = "random_sweep";
  motion.root_positions.resize(3, count);
  motion.root_rpy.resize(3, count);
  motion.joints.resize(joints, count);
  Eigen::VectorXi side(joints), same_side_run(joints);
  for (Eigen::Index j = 0; j < joints; ++j) {
    side(j) = uniform01(rng) < 0.5 ? 0 : 1;
    same_side_run(j) = 0;
  }
  for (Eigen::Index k = 0; k < count; ++k) {
    motion.times.push_back(
        std::min(static_cast<double>(k) * options.keyframe_interval_s, options.duration_s));
    if (k == 0) {
      motion.root_positions.col(0) = Eigen::Vector3d(0, 0, 530);
      motion.root_rpy.col(0).setZero();
      // The zero pose, clamped in case a limit pair excludes 0.
      motion.joints.col(0) = Eigen::VectorXd::Zero(joints).cwiseMax(lower).cwiseMin(upper);
      continue;
    }
    motion.root_positions.col(k) =
        Eigen::Vector3d(uniform(rng, -1, 1) * options.root_wander_mm,
                        uniform(rng, -1, 1) * options.root_wander_mm, 530.0 + uniform(rng, -1, 1) * 20.0);
    motion.root_rpy.col(k) = Eigen::Vector3d(uniform(rng, -1, 1) * options.root_tilt_rad,
                                             uniform(rng, -1, 1) * options.root_tilt_rad,
                                             uniform(rng, -1, 1) * options.root_turn_rad);
    for (Eigen::Index j = 0; j < joints; ++j) {
      const bool flip = same_side_run(j) >= 2 || uniform01(rng) < 0.7;
      if (flip) {
        side(j) = 1 - side(j);
        same_side_run(j) = 0;
      } else {
        ++same_side_run(j);
      }
      const double range = upper(j) - lower(j);
      const double depth = uniform(rng, 0.1, 1.0) * options.limit_band * range;
      motion.joints(j, k) = side(j) == 0 ? lower(j) + depth : upper(j) - depth;
    }
  }
  // A last keyframe shorter than the interval would make it faster; the spacing is uniform
  // because count - 1 intervals of keyframe_interval_s cover duration_s (the last one clipped).
  if (count >= 2 &&
      motion.times[static_cast<std::size_t>(count - 1)] <= motion.times[static_cast<std::size_t>(count - 2)])
    throw std::invalid_argument("random sweep: the duration is too short for the keyframe interval");
  return motion;
}

}  // namespace s2kf::sim
