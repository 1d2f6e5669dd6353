// Optimal LCD sample sets: exact moments, lower distance than UKF and random sets, reproducibility,
// the whitened objective's gradient and the optimiser itself.
#include <s2kf/core/lcd_sample_set.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using s2kf::compute_lcd_sample_set;
using s2kf::LcdOptions;

void expect_exact_moments(const Eigen::MatrixXd& z) {
  const double count = static_cast<double>(z.cols());
  const Eigen::VectorXd mean = z.rowwise().mean();
  const Eigen::MatrixXd covariance = z * z.transpose() / count;
  EXPECT_LT(mean.cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((covariance - Eigen::MatrixXd::Identity(z.rows(), z.rows())).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(LcdSampleSet, HasExactMomentsAndEqualWeights) {
  for (auto [n, l] : {std::pair{3, 31}, std::pair{5, 50}, std::pair{4, 8}, std::pair{1, 5}}) {
    const auto result = compute_lcd_sample_set(n, l);
    ASSERT_EQ(result.set.points.rows(), n);
    ASSERT_EQ(result.set.points.cols(), l);
    expect_exact_moments(result.set.points);
    EXPECT_LT((result.set.weights.array() - 1.0 / l).abs().maxCoeff(), 1e-15);
    EXPECT_EQ(result.set.kind, "lcd");
    EXPECT_FALSE(result.cached);
  }
}

TEST(LcdSampleSet, IsSymmetricWithTheOriginForOddCounts) {
  const auto odd = compute_lcd_sample_set(3, 13);
  EXPECT_EQ(odd.set.points.col(0).norm(), 0.0);
  EXPECT_EQ(Eigen::MatrixXd(odd.set.points.middleCols(1, 6)), Eigen::MatrixXd(-odd.set.points.rightCols(6)));
  const auto even = compute_lcd_sample_set(3, 12);
  EXPECT_EQ(Eigen::MatrixXd(even.set.points.leftCols(6)), Eigen::MatrixXd(-even.set.points.rightCols(6)));
  EXPECT_GT(even.set.points.colwise().norm().minCoeff(), 0.1);
}

TEST(LcdSampleSet, ReportsTheDistanceOfTheReturnedSet) {
  LcdOptions options;
  options.bmax = 7.0;
  const auto result = compute_lcd_sample_set(4, 21, options);
  EXPECT_NEAR(result.distance, s2kf::lcd_distance(result.set.points, 7.0), 1e-12);
  const auto with_default = compute_lcd_sample_set(4, 21);
  EXPECT_NEAR(with_default.distance, s2kf::lcd_distance(with_default.set.points, s2kf::default_bmax(4)),
              1e-12);
}

// With L = 2N + 1 there are N half samples, and exact moments force them to be sqrt(L/2) times an
// orthogonal matrix: the set is the unscented set (kappa = 0.5) up to a rotation, and the distance,
// which only sees norms and distances, must agree exactly. More samples must then do better.
TEST(LcdSampleSet, EqualsTheUnscentedSetAtItsSizeAndBeatsItWithMoreSamples) {
  for (int n : {2, 3, 5}) {
    const s2kf::SampleSet ukf = s2kf::ukf_sample_set(n, 0.5);  // 2N + 1 equally weighted points
    ASSERT_LT((ukf.weights.array() - ukf.weights(0)).abs().maxCoeff(), 1e-15);
    const double bmax = s2kf::default_bmax(n);
    const double ukf_distance = s2kf::lcd_distance(ukf.points, bmax);
    const auto same_size = compute_lcd_sample_set(n, 2 * n + 1);
    EXPECT_NEAR(same_size.distance, ukf_distance, 1e-12) << "N = " << n;
    const auto larger = compute_lcd_sample_set(n, 4 * n + 1);
    EXPECT_LT(larger.distance, 0.8 * ukf_distance) << "N = " << n;
  }
}

TEST(LcdSampleSet, IsCloserToTheNormalThanRandomSetsOfTheSameSize) {
  const int n = 4, l = 41;
  const auto lcd = compute_lcd_sample_set(n, l);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const s2kf::SampleSet random = s2kf::random_sample_set(n, l, seed);
    EXPECT_LT(lcd.distance, 0.5 * s2kf::lcd_distance(random.points, s2kf::default_bmax(n)))
        << "seed " << seed;
  }
}

TEST(LcdSampleSet, MoreSamplesGiveASmallerDistance) {
  const double small = compute_lcd_sample_set(3, 11).distance;
  const double large = compute_lcd_sample_set(3, 41).distance;
  EXPECT_LT(large, small);
}

TEST(LcdSampleSet, IsReproducibleForTheSameSeed) {
  LcdOptions options;
  options.seed = 42;
  const auto a = compute_lcd_sample_set(5, 31, options);
  const auto b = compute_lcd_sample_set(5, 31, options);
  EXPECT_EQ(a.set.points, b.set.points);
  EXPECT_EQ(a.distance, b.distance);
  EXPECT_EQ(a.iterations, b.iterations);
  options.seed = 43;
  const auto c = compute_lcd_sample_set(5, 31, options);
  EXPECT_NE(a.set.points, c.set.points);
  // Local optima differ in position but hardly in distance.
  EXPECT_NEAR(c.distance, a.distance, 0.03 * a.distance);
}

TEST(LcdSampleSet, StopsByTheConfiguredRules) {
  LcdOptions options;
  options.max_iterations = 3;
  const auto capped = compute_lcd_sample_set(6, 40, options);
  EXPECT_EQ(capped.iterations, 3);
  expect_exact_moments(capped.set.points);  // corrected even when stopped early
  const auto full = compute_lcd_sample_set(6, 40);
  EXPECT_GT(full.iterations, 3);
  EXPECT_LT(full.distance, capped.distance);
}

TEST(LcdSampleSet, RejectsImpossibleSizesAndOptions) {
  EXPECT_THROW(compute_lcd_sample_set(3, 5), s2kf::DimensionError);  // L < 2N
  EXPECT_THROW(compute_lcd_sample_set(0, 5), s2kf::DimensionError);
  try {
    compute_lcd_sample_set(46, 91);
    FAIL() << "L < 2N was accepted";
  } catch (const s2kf::DimensionError& error) {
    EXPECT_NE(std::string(error.what()).find("at least 92 samples"), std::string::npos) << error.what();
  }
  LcdOptions options;
  options.bmax = -1.0;
  EXPECT_THROW(compute_lcd_sample_set(2, 5, options), std::invalid_argument);
  options = {};
  options.history = 0;
  EXPECT_THROW(compute_lcd_sample_set(2, 5, options), std::invalid_argument);
}

TEST(LcdSampleSet, WhitenedObjectiveGradientMatchesCentralDifferences) {
  for (auto [n, m, origin] : {std::tuple{3, 5, true}, std::tuple{4, 6, false}}) {
    s2kf::LcdObjective objective(n, s2kf::default_bmax(n));
    s2kf::detail::WhitenedSymmetricObjective whitened(objective, m, origin);
    std::mt19937_64 rng(9);
    std::normal_distribution<double> normal;
    Eigen::VectorXd x(n * m), gradient(n * m), scratch(n * m);
    for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = normal(rng);
    whitened(x, gradient);
    const double h = 1e-3;
    double worst = 0.0;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      auto at = [&](double by) {
        Eigen::VectorXd moved = x;
        moved(i) += by;
        return whitened(moved, scratch);
      };
      const double numeric = (-at(2 * h) + 8 * at(h) - 8 * at(-h) + at(-2 * h)) / (12 * h);
      worst = std::max(worst, std::abs(numeric - gradient(i)));
    }
    EXPECT_LT(worst, 1e-7 * gradient.cwiseAbs().maxCoeff()) << "N = " << n;
    // The value is that of the moment-corrected set.
    Eigen::MatrixXd set = s2kf::detail::symmetric_set(whitened.whiten(x), origin);
    const double value = whitened(x, scratch);
    s2kf::correct_moments(set);
    EXPECT_NEAR(value + objective.d1(), objective.distance(set), 1e-11);
  }
}

TEST(Lbfgs, MinimisesTheRosenbrockFunction) {
  auto rosenbrock = [](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    double value = 0.0;
    g.setZero();
    for (Eigen::Index i = 0; i + 1 < x.size(); ++i) {
      const double a = x(i + 1) - x(i) * x(i), b = 1.0 - x(i);
      value += 100.0 * a * a + b * b;
      g(i) += -400.0 * a * x(i) - 2.0 * b;
      g(i + 1) += 200.0 * a;
    }
    return value;
  };
  Eigen::VectorXd x = Eigen::VectorXd::Constant(6, -1.2);
  const auto report = s2kf::detail::minimize_lbfgs(rosenbrock, x, 10, 1000, 1e-10, 0.0, 0.0);
  EXPECT_LT((x - Eigen::VectorXd::Ones(6)).cwiseAbs().maxCoeff(), 1e-7) << report.stop;
  EXPECT_STREQ(report.stop, "gradient tolerance");
}

TEST(BoxMuller, DrawsStandardNormalNumbersReproducibly) {
  s2kf::detail::BoxMuller a(5), b(5);
  double sum = 0.0, squares = 0.0;
  const int count = 200000;
  for (int i = 0; i < count; ++i) {
    const double z = a();
    ASSERT_EQ(z, b());
    sum += z;
    squares += z * z;
  }
  EXPECT_NEAR(sum / count, 0.0, 0.01);       // 4.5 standard errors
  EXPECT_NEAR(squares / count, 1.0, 0.015);  // 4.7 standard errors
}

}  // namespace
