// The filter with a state dimension fixed at compile time, against the dynamic-size filter. It
// lives in the header-only test program: the fixed-size filter is compiled wherever it is used
// (only the dynamic-size one comes from the compiled library), which costs about 20 s of compiling
// in a program that does not compile the library's Eigen kernels anyway.
#include <s2kf/core/sample_set.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>

#include <gtest/gtest.h>

#include <random>

namespace {

struct FixedSizeLinearModel {
  Eigen::MatrixXd h;
  void operator()(const Eigen::MatrixXd& x, Eigen::MatrixXd& y) const { y = h * x; }
};

TEST(S2kfLinear, FixedSizeStateGivesTheSameResultAsDynamic) {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> normal;
  Eigen::Matrix2d a;
  for (int i = 0; i < 4; ++i) a.data()[i] = normal(rng);
  const Eigen::Matrix2d c = a * a.transpose() + 0.5 * Eigen::Matrix2d::Identity();
  FixedSizeLinearModel model{Eigen::MatrixXd(1, 2)};
  model.h << normal(rng), normal(rng);

  s2kf::SmartSamplingKalmanFilter<2> fixed_filter(s2kf::ukf_sample_set(2));
  s2kf::S2kf dynamic_filter(s2kf::ukf_sample_set(2));
  s2kf::Gaussian<double, 2> fixed(Eigen::Vector2d(1, 2), c);
  s2kf::GaussianXd dynamic(Eigen::VectorXd(fixed.mean), Eigen::MatrixXd(c));
  const Eigen::MatrixXd r = Eigen::MatrixXd::Constant(1, 1, 0.3);
  const Eigen::VectorXd y = Eigen::VectorXd::Constant(1, 0.7);
  ASSERT_TRUE(fixed_filter.update(fixed, model, y, r).ok());
  ASSERT_TRUE(dynamic_filter.update(dynamic, model, y, r).ok());
  // The update moved the state (so the comparison below is not of two untouched priors).
  EXPECT_GT((dynamic.mean - Eigen::VectorXd(Eigen::Vector2d(1, 2))).norm(), 1e-3);
  EXPECT_LT((fixed.mean - dynamic.mean).norm(), 1e-14);
  EXPECT_LT((fixed.covariance - dynamic.covariance).norm(), 1e-14);
  EXPECT_THROW(s2kf::SmartSamplingKalmanFilter<3>(s2kf::ukf_sample_set(2)), s2kf::DimensionError);
}

}  // namespace
