// Keyframe motions, their interpolation, and the random sweep generator.
#include <s2kf/sim/keyframe_motion.hpp>
#include <s2kf/sim/random_sweep.hpp>

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace {

using namespace s2kf::sim;

KeyframeMotion two_joint_motion() {
  KeyframeMotion motion;
  motion.name = "test";
  motion.times = {0.0, 1.0, 2.5};
  motion.root_positions.resize(3, 3);
  motion.root_positions << 0, 100, 100, 0, 0, 50, 530, 500, 530;
  motion.root_rpy = Eigen::Matrix3Xd::Zero(3, 3);
  motion.root_rpy(1, 2) = 6.0;  // a full turn of pitch is allowed: the root has no limits
  motion.joints.resize(2, 3);
  motion.joints << 0.0, 1.0, 0.5, -0.2, -0.2, 0.3;
  return motion;
}

TEST(InterpolatedMotion, HitsTheKeyframesAndHoldsTheEnds) {
  const KeyframeMotion motion = two_joint_motion();
  const InterpolatedMotion trajectory(motion);
  for (Eigen::Index k = 0; k < 3; ++k) {
    const MotionSample sample = trajectory.at(motion.times[static_cast<std::size_t>(k)]);
    EXPECT_TRUE(sample.root_position.isApprox(motion.root_positions.col(k)));
    EXPECT_NEAR((sample.root_rpy - motion.root_rpy.col(k)).norm(), 0.0, 1e-12);
    EXPECT_NEAR((sample.joints - motion.joints.col(k)).norm(), 0.0, 1e-12);
  }
  EXPECT_NEAR((trajectory.at(10.0).joints - motion.joints.col(2)).norm(), 0.0, 0.0);
  EXPECT_EQ(trajectory.velocity_at(10.0).joints.norm(), 0.0);
  // A flat stretch in the keyframes (joint 1 from 0 to 1 s) stays exactly flat.
  for (double t = 0.0; t <= 1.0; t += 0.05) EXPECT_EQ(trajectory.at(t).joints(1), -0.2);
}

TEST(InterpolatedMotion, VelocityIsTheDerivativeOfThePosition) {
  const InterpolatedMotion trajectory(two_joint_motion());
  const double h = 1e-6;
  for (double t = 0.05; t < 2.45; t += 0.1) {
    const MotionSample v = trajectory.velocity_at(t);
    const MotionSample plus = trajectory.at(t + h), minus = trajectory.at(t - h);
    EXPECT_NEAR((v.joints - (plus.joints - minus.joints) / (2 * h)).norm(), 0.0, 1e-5) << t;
    EXPECT_NEAR((v.root_position - (plus.root_position - minus.root_position) / (2 * h)).norm(), 0.0, 1e-3)
        << t;
  }
}

TEST(ValidateMotion, NamesTheJointAndKeyframeOutsideTheLimits) {
  KeyframeMotion motion = two_joint_motion();
  const Eigen::Vector2d lower(-1.0, -0.5), upper(1.0, 0.5);
  EXPECT_NO_THROW(validate_motion(motion, lower, upper, {"A", "B"}));
  motion.joints(1, 2) = 0.6;
  try {
    validate_motion(motion, lower, upper, {"A", "B"});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("keyframe 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("joint B"), std::string::npos) << e.what();
  }
  motion = two_joint_motion();
  motion.times[1] = 0.0;
  EXPECT_THROW(validate_motion(motion, lower, upper), std::invalid_argument);
  motion = two_joint_motion();
  EXPECT_THROW(validate_motion(motion, Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()),
               std::invalid_argument);
}

// Limits as in the body-model table, a few joints with asymmetric and one-sided ranges.
const Eigen::Vector4d kLower(-0.872665, 0.0, -2.26893, -0.349066);
const Eigen::Vector4d kUpper(0.610865, 2.79253, 0.0, 0.349066);

TEST(RandomSweep, StaysWithinTheLimitsAndSweepsMostOfEveryRange) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const KeyframeMotion motion = random_sweep_motion(seed, kLower, kUpper);
    ASSERT_NO_THROW(validate_motion(motion, kLower, kUpper));
    const InterpolatedMotion trajectory(motion);
    Eigen::Vector4d low = Eigen::Vector4d::Constant(1e9), high = Eigen::Vector4d::Constant(-1e9);
    for (double t = motion.start_time(); t <= motion.end_time(); t += 0.01) {
      const Eigen::VectorXd q = trajectory.at(t).joints;
      ASSERT_TRUE((q.array() >= kLower.array()).all() && (q.array() <= kUpper.array()).all()) << t;
      low = low.cwiseMin(q);
      high = high.cwiseMax(q);
    }
    const Eigen::Vector4d range = kUpper - kLower;
    for (int j = 0; j < 4; ++j) {
      EXPECT_LE(low(j), kLower(j) + 0.2 * range(j)) << "seed " << seed << " joint " << j;
      EXPECT_GE(high(j), kUpper(j) - 0.2 * range(j)) << "seed " << seed << " joint " << j;
    }
  }
}

TEST(RandomSweep, IsDeterminedByItsSeed) {
  const KeyframeMotion a = random_sweep_motion(7, kLower, kUpper), b = random_sweep_motion(7, kLower, kUpper),
                       c = random_sweep_motion(8, kLower, kUpper);
  EXPECT_EQ(a.joints, b.joints);
  EXPECT_EQ(a.root_positions, b.root_positions);
  EXPECT_NE(a.joints, c.joints);
  EXPECT_EQ(a.keyframe_count(), 13);
  EXPECT_DOUBLE_EQ(a.end_time(), 12.0);
}

TEST(RandomSweep, RejectsBadOptions) {
  RandomSweepOptions options;
  options.duration_s = -1;
  EXPECT_THROW(random_sweep_motion(1, kLower, kUpper, options), std::invalid_argument);
  EXPECT_THROW(random_sweep_motion(1, kUpper, kLower), std::invalid_argument);
}

}  // namespace
