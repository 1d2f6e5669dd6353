/// @file
/// Soft-tissue artefact: a skin marker slides over the bone it is meant to follow, by about a
/// centimetre, in step with the joints that bend the skin under it and with slow drift.
#pragma once

#include <s2kf/core/constants.hpp>
#include <s2kf/sim/random.hpp>

#include <Eigen/Core>

#include <cmath>
#include <random>
#include <vector>

namespace s2kf::sim {

/// The soft-tissue offset of one marker, in the frame of the segment it rides on (mm):
///   s(t) = sum_j g_j u_j(t) + a * sin(2 pi f t + phi)   (per coordinate)
/// with u_j = (q_j - mid_j) / half_range_j in [-1, 1] the normalised angle of joint j of the
/// marker's own joint group (the joints whose motion folds the skin under it) and a slow sinusoidal
/// drift (0.1 to 0.5 Hz). Gains and drift are drawn once per subject; the offset is then a smooth
/// function of the motion, like the real artefact, which is why a filter cannot average it away.
struct SoftTissue {
  std::vector<Eigen::Index> joints;  ///< indices into the joint vector
  Eigen::Matrix3Xd gains;            ///< mm per unit normalised angle, one column per joint
  Eigen::Vector3d drift_amplitude = Eigen::Vector3d::Zero();  ///< mm
  Eigen::Vector3d drift_frequency = Eigen::Vector3d::Zero();  ///< Hz
  Eigen::Vector3d drift_phase = Eigen::Vector3d::Zero();      ///< rad

  Eigen::Vector3d offset(const Eigen::VectorXd& angles, const Eigen::VectorXd& lower,
                         const Eigen::VectorXd& upper, double time_s) const {
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < joints.size(); ++i) {
      const Eigen::Index j = joints[i];
      const double half_range = 0.5 * (upper(j) - lower(j));
      if (half_range > 0.0)
        s += gains.col(static_cast<Eigen::Index>(i)) *
             ((angles(j) - 0.5 * (upper(j) + lower(j))) / half_range);
    }
    for (int c = 0; c < 3; ++c)
      s(c) += drift_amplitude(c) * std::sin(2.0 * kPi * drift_frequency(c) * time_s + drift_phase(c));
    return s;
  }
};

/// Draws a marker's soft-tissue model with scale `amplitude_mm`: each coordinate gets gains of
/// SD 0.8 amplitude / sqrt(number of joints) (so the joint-driven part has an SD of about
/// 0.8 amplitude per coordinate over a motion that spans the ranges) and a drift of amplitude
/// 0.6 amplitude * |N(0,1)| (all of it, 1.0, for markers whose segment has no joint of its own).
/// Over the bundled motions the 3D offset is then about 1.0 amplitude RMS, 2.5 amplitude at most.
inline SoftTissue draw_soft_tissue(const std::vector<Eigen::Index>& joints, double amplitude_mm,
                                   std::mt19937_64& rng) {
  SoftTissue tissue;
  tissue.joints = joints;
  tissue.gains.resize(3, static_cast<Eigen::Index>(joints.size()));
  const double gain_sd =
      joints.empty() ? 0.0 : 0.8 * amplitude_mm / std::sqrt(static_cast<double>(joints.size()));
  for (Eigen::Index i = 0; i < tissue.gains.cols(); ++i)
    for (int c = 0; c < 3; ++c) tissue.gains(c, i) = gain_sd * standard_normal(rng);
  const double drift = (joints.empty() ? 1.0 : 0.6) * amplitude_mm;
  for (int c = 0; c < 3; ++c) {
    tissue.drift_amplitude(c) = drift * std::abs(standard_normal(rng));
    tissue.drift_frequency(c) = uniform(rng, 0.1, 0.5);
    tissue.drift_phase(c) = uniform(rng, 0.0, 2.0 * kPi);
  }
  return tissue;
}

}  // namespace s2kf::sim
