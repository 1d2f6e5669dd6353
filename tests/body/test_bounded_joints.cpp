// The bounded joint map theta = (u - l)/2 sin(Theta) + (u + l)/2.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/bounded_joints.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace {

using s2kf::body::BoundedJoints;
using s2kf::body::kJointCount;
using s2kf::body::mmm_body_model;

TEST(BoundedJoints, ZeroParameterIsTheMiddleAndPlusMinusHalfPiAreTheLimits) {
  const BoundedJoints joints(mmm_body_model());
  const Eigen::VectorXd middle = joints.angles(Eigen::VectorXd::Zero(kJointCount));
  const Eigen::VectorXd top = joints.angles(Eigen::VectorXd::Constant(kJointCount, M_PI / 2));
  const Eigen::VectorXd bottom = joints.angles(Eigen::VectorXd::Constant(kJointCount, -M_PI / 2));
  // LKx: [-2.26893, 0].
  EXPECT_DOUBLE_EQ(middle(29), -2.26893 / 2);
  EXPECT_DOUBLE_EQ(top(29), 0);
  EXPECT_DOUBLE_EQ(bottom(29), -2.26893);
  EXPECT_TRUE(top.isApprox(joints.upper.matrix(), 1e-15));
  EXPECT_TRUE(bottom.isApprox(joints.lower.matrix(), 1e-15));
}

TEST(BoundedJoints, AnyFiniteParameterGivesAnAngleWithinLimits) {
  const BoundedJoints joints(mmm_body_model());
  std::mt19937 rng(4);
  for (double scale : {1.0, 10.0, 1e6, 1e9, 1e300}) {
    std::uniform_real_distribution<double> unit(-scale, scale);
    Eigen::VectorXd parameters(kJointCount);
    for (int j = 0; j < kJointCount; ++j) parameters(j) = unit(rng);
    EXPECT_TRUE(joints.within_limits(joints.angles(parameters))) << scale;
  }
  EXPECT_TRUE(joints.within_limits(joints.angles(Eigen::VectorXd::Constant(kJointCount, 1e6))));
  EXPECT_TRUE(joints.within_limits(joints.angles(Eigen::VectorXd::Constant(kJointCount, -1e9))));
}

TEST(BoundedJoints, NonFiniteParametersGiveNaNSoTheFilterNoticesExceptOnFixedJoints) {
  Eigen::ArrayXd lower(3), upper(3);
  lower << -1, 0.5, 0;
  upper << 1, 0.5, 2;
  const BoundedJoints joints(lower, upper);
  Eigen::VectorXd parameters(3);
  parameters << std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(),
      std::numeric_limits<double>::infinity();
  const Eigen::VectorXd angles = joints.angles(parameters);
  EXPECT_TRUE(std::isnan(angles(0)));
  EXPECT_EQ(angles(1), 0.5);
  EXPECT_TRUE(std::isnan(angles(2)));
  EXPECT_FALSE(joints.within_limits(angles));
}

TEST(BoundedJoints, InverseRoundTripsAndClampsBeyondTheLimits) {
  const BoundedJoints joints(mmm_body_model());
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> unit(0, 1);
  Eigen::VectorXd angles(kJointCount);
  for (int j = 0; j < kJointCount; ++j)
    angles(j) = joints.lower(j) + unit(rng) * (joints.upper(j) - joints.lower(j));
  const Eigen::VectorXd parameters = joints.parameters(angles);
  EXPECT_TRUE((parameters.array().abs() <= M_PI / 2).all());
  const Eigen::VectorXd back = joints.angles(parameters);
  EXPECT_TRUE(back.isApprox(angles, 1e-12));
  // Theta on another branch maps back to the principal one with the same angle.
  const Eigen::VectorXd other_branch = (M_PI - parameters.array()).matrix();
  const Eigen::VectorXd principal = joints.parameters(joints.angles(other_branch));
  EXPECT_TRUE(principal.isApprox(parameters, 1e-7));
  const Eigen::VectorXd beyond = joints.upper.matrix() + Eigen::VectorXd::Ones(kJointCount);
  const Eigen::VectorXd at_limit = joints.parameters(beyond);
  for (int j = 0; j < kJointCount; ++j) EXPECT_DOUBLE_EQ(at_limit(j), M_PI / 2);
}

TEST(BoundedJoints, DerivativeMatchesCentralDifferences) {
  const BoundedJoints joints(mmm_body_model());
  Eigen::VectorXd parameters = Eigen::VectorXd::LinSpaced(kJointCount, -2, 3);
  const Eigen::VectorXd derivative = joints.derivative(parameters);
  const double h = 1e-6;
  for (int j = 0; j < kJointCount; ++j) {
    Eigen::VectorXd plus = parameters, minus = parameters;
    plus(j) += h;
    minus(j) -= h;
    EXPECT_NEAR(derivative(j), (joints.angles(plus)(j) - joints.angles(minus)(j)) / (2 * h), 1e-8);
  }
}

TEST(BoundedJoints, FixedJointsStayFixed) {
  Eigen::ArrayXd lower(2), upper(2);
  lower << 0.3, -1;
  upper << 0.3, 1;
  const BoundedJoints joints(lower, upper);
  for (double p : {-7.0, 0.0, 1.0, 1e9}) {
    EXPECT_EQ(joints.angles(Eigen::Vector2d(p, p))(0), 0.3);
    EXPECT_EQ(joints.parameters(Eigen::Vector2d(p, 0))(0), 0.0);
    EXPECT_EQ(joints.derivative(Eigen::Vector2d(p, 0))(0), 0.0);
  }
  EXPECT_THROW(BoundedJoints(upper, lower), std::invalid_argument);
  EXPECT_THROW(joints.angles(Eigen::VectorXd::Zero(3)), s2kf::DimensionError);
}

}  // namespace
