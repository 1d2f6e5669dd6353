// MarginalUpdate against the full Kalman update: a linear measurement of the first components of
// [p, v] updates p's marginal (by the ordinary formulas), and MarginalUpdate carries it to v; the
// result must equal the Kalman update of the whole state with the measurement matrix [H 0].
#include <s2kf/core/marginal_update.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>

namespace {

using namespace s2kf;

Eigen::MatrixXd random_covariance(int d, std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd a(d, d);
  for (int i = 0; i < d; ++i)
    for (int j = 0; j < d; ++j) a(i, j) = normal(rng);
  return a * a.transpose() + 0.5 * Eigen::MatrixXd::Identity(d, d);
}

GaussianXd kalman_update(const GaussianXd& prior, const Eigen::MatrixXd& h, const Eigen::VectorXd& y,
                         const Eigen::MatrixXd& r) {
  const Eigen::MatrixXd s = h * prior.covariance * h.transpose() + r;
  const Eigen::MatrixXd gain = prior.covariance * h.transpose() * s.inverse();
  GaussianXd posterior;
  posterior.mean = prior.mean + gain * (y - h * prior.mean);
  posterior.covariance = prior.covariance - gain * s * gain.transpose();
  return posterior;
}

TEST(MarginalUpdate, EqualsTheKalmanUpdateOfTheWholeState) {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 5; ++trial) {
    const int n = 4, m = 3 + trial % 2, d = n + m, measured = 2 + trial % 3;
    GaussianXd prior(Eigen::VectorXd::NullaryExpr(d, [&] { return normal(rng); }), random_covariance(d, rng));
    const Eigen::MatrixXd hp = Eigen::MatrixXd::NullaryExpr(measured, n, [&] { return normal(rng); });
    Eigen::MatrixXd h = Eigen::MatrixXd::Zero(measured, d);
    h.leftCols(n) = hp;
    const Eigen::VectorXd y = Eigen::VectorXd::NullaryExpr(measured, [&] { return 3 * normal(rng); });
    const Eigen::MatrixXd r = random_covariance(measured, rng);

    const GaussianXd full = kalman_update(prior, h, y, r);
    const GaussianXd head(prior.mean.head(n), prior.covariance.topLeftCorner(n, n));
    const GaussianXd head_posterior = kalman_update(head, hp, y, r);
    GaussianXd joint = prior;
    MarginalUpdate update;
    ASSERT_TRUE(update.apply(joint, head_posterior));
    EXPECT_LT((joint.mean - full.mean).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    EXPECT_LT((joint.covariance - full.covariance).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    // The rates moved: the test is not passing because nothing changed.
    EXPECT_GT((joint.mean.tail(m) - prior.mean.tail(m)).norm(), 1e-3);
  }
}

TEST(MarginalUpdate, RefusesWhatDoesNotFitAndKeepsTheStateOnFailure) {
  GaussianXd joint(Eigen::VectorXd::Zero(4), Eigen::MatrixXd::Identity(4, 4));
  MarginalUpdate update;
  EXPECT_THROW(update.apply(joint, GaussianXd(Eigen::VectorXd::Zero(5), Eigen::MatrixXd::Identity(5, 5))),
               DimensionError);
  joint.covariance.topLeftCorner(2, 2).setZero();  // no Cholesky factor
  const GaussianXd before = joint;
  EXPECT_FALSE(update.apply(joint, GaussianXd(Eigen::VectorXd::Ones(2), Eigen::MatrixXd::Identity(2, 2))));
  EXPECT_EQ(joint.mean, before.mean);
  EXPECT_EQ(joint.covariance, before.covariance);
}

}  // namespace
