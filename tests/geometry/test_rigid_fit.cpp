#include <s2kf/geometry/rigid_fit.hpp>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <random>

namespace {

using s2kf::geometry::fit_rigid_transform;
using s2kf::geometry::RigidTransform;

Eigen::Matrix3Xd random_points(int count, std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 300.0);  // mm, a body's spread
  Eigen::Matrix3Xd points(3, count);
  for (int k = 0; k < count; ++k) points.col(k) << normal(rng), normal(rng), normal(rng);
  return points;
}

Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  return Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng))
      .normalized()
      .toRotationMatrix();
}

double cost(const RigidTransform& fit, const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to) {
  return ((fit.rotation * from).colwise() + fit.translation - to).squaredNorm();
}

TEST(RigidFit, RecoversAnExactRotationAndTranslation) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix3Xd from = random_points(trial % 2 ? 3 : 12, rng);  // three points suffice
    const Eigen::Matrix3d rotation = random_rotation(rng);
    const Eigen::Vector3d translation(100.0 * trial, -250.0, 900.0);
    const Eigen::Matrix3Xd to = (rotation * from).colwise() + translation;
    const RigidTransform fit = fit_rigid_transform(from, to);
    EXPECT_LT((fit.rotation - rotation).norm(), 1e-12) << trial;
    EXPECT_LT((fit.translation - translation).norm(), 1e-9) << trial;
  }
}

TEST(RigidFit, NoisyPointsGiveTheLeastSquaresRotationNeverAReflection) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 5.0);
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Matrix3Xd from = random_points(8, rng);
    Eigen::Matrix3Xd to = (random_rotation(rng) * from).colwise() + Eigen::Vector3d(10, 20, 30);
    for (Eigen::Index k = 0; k < to.size(); ++k) to(k) += noise(rng);
    const RigidTransform fit = fit_rigid_transform(from, to);
    EXPECT_NEAR(fit.rotation.determinant(), 1.0, 1e-12);
    EXPECT_LT((fit.rotation.transpose() * fit.rotation - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    // A minimum: a small turn about any axis, with the translation refitted (the centroids
    // matched), costs more.
    const double best = cost(fit, from, to);
    for (int axis = 0; axis < 3; ++axis)
      for (double angle : {-1e-3, 1e-3}) {
        RigidTransform turned;
        turned.rotation = Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)) * fit.rotation;
        turned.translation = to.rowwise().mean() - turned.rotation * from.rowwise().mean();
        EXPECT_GT(cost(turned, from, to), best) << trial << " axis " << axis;
      }
  }
  // A mirror image has no rotation that maps it exactly: the answer is still a rotation.
  const Eigen::Matrix3Xd from = random_points(6, rng);
  const Eigen::Matrix3Xd mirrored = Eigen::Vector3d(-1, 1, 1).asDiagonal() * from;
  EXPECT_NEAR(fit_rigid_transform(from, mirrored).rotation.determinant(), 1.0, 1e-12);
}

}  // namespace
