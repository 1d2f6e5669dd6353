/// @file
/// A motion given as keyframes of the root and joint channels, and its smooth, limit-respecting
/// trajectory (monotone cubic interpolation per channel).
#pragma once

#include <s2kf/sim/monotone_cubic.hpp>

#include <Eigen/Core>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::sim {

/// The subject height the root positions of a KeyframeMotion refer to; a subject of height H
/// moves its root by the keyframe positions times H / kReferenceHeightMm.
inline constexpr double kReferenceHeightMm = 1000.0;

/// Keyframes of a whole-body motion. Column i of every matrix belongs to times[i].
struct KeyframeMotion {
  std::string name;
  std::vector<double> times;        ///< s, strictly increasing
  Eigen::Matrix3Xd root_positions;  ///< mm, for a subject of height kReferenceHeightMm
  Eigen::Matrix3Xd root_rpy;        ///< rad, R_root = Rz(yaw) Ry(pitch) Rx(roll)
  Eigen::MatrixXd joints;           ///< rad, one row per joint in the body model's state order

  Eigen::Index keyframe_count() const { return static_cast<Eigen::Index>(times.size()); }
  Eigen::Index joint_count() const { return joints.rows(); }
  double start_time() const { return times.front(); }
  double end_time() const { return times.back(); }
};

/// The channels of a motion at one instant (root position still at the reference height).
struct MotionSample {
  Eigen::Vector3d root_position;  ///< mm at kReferenceHeightMm
  Eigen::Vector3d root_rpy;       ///< rad
  Eigen::VectorXd joints;         ///< rad
};

/// Checks the shape of `motion` and that every keyframe lies within [lower, upper] (rad, per
/// joint). Throws std::invalid_argument with a sentence naming the keyframe and the joint
/// (`joint_names` may be empty, then joints are named by index).
inline void validate_motion(const KeyframeMotion& motion, const Eigen::VectorXd& lower,
                            const Eigen::VectorXd& upper, const std::vector<std::string>& joint_names = {}) {
  const std::string what = "motion '" + motion.name + "'";
  const Eigen::Index n = motion.keyframe_count();
  if (n == 0) throw std::invalid_argument(what + " has no keyframes");
  if (motion.root_positions.cols() != n || motion.root_rpy.cols() != n || motion.joints.cols() != n)
    throw std::invalid_argument(what + ": every channel needs one value per keyframe");
  if (motion.joints.rows() != lower.size() || lower.size() != upper.size())
    throw std::invalid_argument(what + " has " + std::to_string(motion.joints.rows()) +
                                " joints but the limits have " + std::to_string(lower.size()));
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = motion.times[static_cast<std::size_t>(k)];
    std::ostringstream at;
    at << what << ", keyframe " << k << " (t = " << t << " s)";
    if (!std::isfinite(t)) throw std::invalid_argument(at.str() + ": the time is not finite");
    if (k > 0 && !(t > motion.times[static_cast<std::size_t>(k - 1)]))
      throw std::invalid_argument(at.str() + ": keyframe times must be strictly increasing");
    if (!motion.root_positions.col(k).allFinite() || !motion.root_rpy.col(k).allFinite() ||
        !motion.joints.col(k).allFinite())
      throw std::invalid_argument(at.str() + ": a value is not finite");
    for (Eigen::Index j = 0; j < motion.joints.rows(); ++j) {
      const double q = motion.joints(j, k);
      if (q < lower(j) || q > upper(j)) {
        std::ostringstream message;
        message << at.str() << ": joint "
                << (static_cast<std::size_t>(j) < joint_names.size()
                        ? joint_names[static_cast<std::size_t>(j)]
                        : "#" + std::to_string(j))
                << " = " << q << " rad lies outside its limits [" << lower(j) << ", " << upper(j) << "]";
        throw std::invalid_argument(message.str());
      }
    }
  }
}

/// The trajectory of a KeyframeMotion: every channel interpolated by a MonotoneCubic, so the
/// trajectory is C1 and never leaves the range of the two keyframes around any instant.
class InterpolatedMotion {
 public:
  explicit InterpolatedMotion(const KeyframeMotion& motion)
      : start_(motion.start_time()), end_(motion.end_time()) {
    const auto channel = [&](auto row) {
      std::vector<double> values(motion.times.size());
      for (std::size_t k = 0; k < values.size(); ++k) values[k] = row(static_cast<Eigen::Index>(k));
      return MonotoneCubic(motion.times, std::move(values));
    };
    if (motion.times.empty()) throw std::invalid_argument("motion '" + motion.name + "' has no keyframes");
    for (int c = 0; c < 3; ++c)
      channels_.push_back(channel([&](Eigen::Index k) { return motion.root_positions(c, k); }));
    for (int c = 0; c < 3; ++c)
      channels_.push_back(channel([&](Eigen::Index k) { return motion.root_rpy(c, k); }));
    for (Eigen::Index j = 0; j < motion.joints.rows(); ++j)
      channels_.push_back(channel([&](Eigen::Index k) { return motion.joints(j, k); }));
  }

  double start_time() const { return start_; }
  double end_time() const { return end_; }

  /// The channels at time t (s); before the first or after the last keyframe the end pose holds.
  MotionSample at(double t) const { return evaluate(t, false); }

  /// The time derivatives of the channels at t (mm/s at the reference height, rad/s).
  MotionSample velocity_at(double t) const { return evaluate(t, true); }

 private:
  MotionSample evaluate(double t, bool derivative) const {
    MotionSample sample;
    sample.joints.resize(static_cast<Eigen::Index>(channels_.size()) - 6);
    for (std::size_t c = 0; c < channels_.size(); ++c) {
      const double v = derivative ? channels_[c].derivative(t) : channels_[c](t);
      if (c < 3)
        sample.root_position(static_cast<Eigen::Index>(c)) = v;
      else if (c < 6)
        sample.root_rpy(static_cast<Eigen::Index>(c) - 3) = v;
      else
        sample.joints(static_cast<Eigen::Index>(c) - 6) = v;
    }
    return sample;
  }

  double start_, end_;
  std::vector<MonotoneCubic> channels_;
};

}  // namespace s2kf::sim
