#include <s2kf/core/constants.hpp>
#include <s2kf/sim/soft_tissue.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using s2kf::sim::draw_soft_tissue;
using s2kf::sim::SoftTissue;

TEST(SoftTissue, OffsetIsLinearInTheNormalisedAnglesPlusTheDrift) {
  SoftTissue tissue;
  tissue.joints = {1, 3};
  tissue.gains.resize(3, 2);
  tissue.gains << 2, -4, 1, 0, 0, 6;
  const Eigen::VectorXd lower = Eigen::VectorXd::Constant(5, -1.0), upper = Eigen::VectorXd::Constant(5, 2.0);
  Eigen::VectorXd angles = Eigen::VectorXd::Constant(5, 0.5);  // mid-range: no joint part
  EXPECT_LT(tissue.offset(angles, lower, upper, 0.0).norm(), 1e-15);
  angles(1) = 2.0;   // joint 1 at its upper limit: +1
  angles(3) = -1.0;  // joint 3 at its lower limit: -1
  angles(0) = 9.0;   // not one of the marker's joints
  EXPECT_LT((tissue.offset(angles, lower, upper, 0.0) - Eigen::Vector3d(2 + 4, 1 - 0, 0 - 6)).norm(), 1e-12);
  // A joint without range adds nothing.
  Eigen::VectorXd fixed_upper = upper;
  fixed_upper(3) = lower(3);
  EXPECT_LT((tissue.offset(angles, lower, fixed_upper, 0.0) - Eigen::Vector3d(2, 1, 0)).norm(), 1e-12);
  // The drift: a * sin(2 pi f t + phi) per coordinate.
  tissue.drift_amplitude = Eigen::Vector3d(3, 0, 1);
  tissue.drift_frequency = Eigen::Vector3d(0.25, 0.1, 0.5);
  tissue.drift_phase = Eigen::Vector3d(0, 1, s2kf::kPi / 2);
  angles.setConstant(0.5);
  const Eigen::Vector3d drift = tissue.offset(angles, lower, upper, 1.0);  // a quarter turn at 0.25 Hz
  EXPECT_NEAR(drift(0), 3.0, 1e-12);
  EXPECT_NEAR(drift(1), 0.0, 1e-12);
  EXPECT_NEAR(drift(2), std::sin(s2kf::kPi + s2kf::kPi / 2), 1e-12);
}

TEST(SoftTissue, DrawnModelsHaveTheStatedScale) {
  std::mt19937_64 rng(3);
  const double amplitude = 10.0;  // mm
  const std::vector<Eigen::Index> joints = {0, 1, 2, 3};
  double gain_square = 0, drift_square = 0;
  int gains = 0, drifts = 0;
  for (int draw = 0; draw < 2000; ++draw) {
    const SoftTissue tissue = draw_soft_tissue(joints, amplitude, rng);
    ASSERT_EQ(tissue.gains.cols(), 4);
    gain_square += tissue.gains.squaredNorm();
    gains += static_cast<int>(tissue.gains.size());
    drift_square += tissue.drift_amplitude.squaredNorm();
    drifts += 3;
    for (int c = 0; c < 3; ++c) {
      EXPECT_GE(tissue.drift_frequency(c), 0.1);
      EXPECT_LE(tissue.drift_frequency(c), 0.5);
      EXPECT_GE(tissue.drift_amplitude(c), 0.0);
    }
  }
  // Gains of SD 0.8 amplitude / sqrt(joints); drift 0.6 amplitude |N(0,1)| (RMS 0.6 amplitude).
  EXPECT_NEAR(std::sqrt(gain_square / gains), 0.8 * amplitude / 2, 0.1);
  EXPECT_NEAR(std::sqrt(drift_square / drifts), 0.6 * amplitude, 0.3);
  // A segment without joints of its own: all of its artefact is drift, of RMS amplitude.
  double alone_square = 0;
  for (int draw = 0; draw < 2000; ++draw)
    alone_square += draw_soft_tissue({}, amplitude, rng).drift_amplitude.squaredNorm();
  EXPECT_NEAR(std::sqrt(alone_square / 6000), amplitude, 0.5);
}

}  // namespace
