// The S2KF against the closed-form Kalman filter, its failure reports, and the iterated update.
#include <s2kf/core/lcd_sample_set.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>

#include "kalman_reference.hpp"

#include <gtest/gtest.h>
#include <Eigen/LU>

#include <cmath>
#include <random>
#include <vector>

namespace {

using s2kf::FilterStatus;
using s2kf::GaussianXd;
using s2kf::ObservedMask;
using s2kf::S2kf;
using s2kf::SampleSet;

using s2kf::test::kalman_update;
using s2kf::test::LinearModel;
using s2kf::test::random_matrix;
using s2kf::test::random_spd;
using s2kf::test::relative_error;

std::vector<SampleSet> sample_sets_of_dimension(int n) {
  // The optimal LCD sets (odd count: with the origin; even: without) are the filter's default;
  // computed here, not taken from the disk cache.
  return {s2kf::ukf_sample_set(n), s2kf::ukf_sample_set(n, 2.0), s2kf::random_sample_set(n, 7 * n, 3),
          s2kf::compute_lcd_sample_set(n, 10 * n + 1).set, s2kf::compute_lcd_sample_set(n, 6 * n).set};
}

TEST(SampleSets, UkfAndRandomSetsHaveExactMoments) {
  for (const SampleSet& set : sample_sets_of_dimension(5)) {
    const Eigen::VectorXd mean = set.points * set.weights;
    const Eigen::MatrixXd cov = set.points * set.weights.asDiagonal() * set.points.transpose();
    EXPECT_LT(mean.norm(), 1e-13) << set.kind;
    EXPECT_LT((cov - Eigen::MatrixXd::Identity(5, 5)).norm(), 1e-12) << set.kind;
    EXPECT_NEAR(set.weights.sum(), 1.0, 1e-14);
  }
  EXPECT_THROW(s2kf::random_sample_set(5, 5, 1), s2kf::DimensionError);
  EXPECT_THROW(s2kf::ukf_sample_set(0), s2kf::DimensionError);
}

TEST(SampleSets, CorrectMomentsMakesMeanZeroAndCovarianceIdentity) {
  std::mt19937_64 rng(11);
  Eigen::MatrixXd z = random_matrix(3, 40, rng).array() * 3.0 + 1.0;
  s2kf::correct_moments(z);
  EXPECT_LT(z.rowwise().mean().norm(), 1e-14);
  EXPECT_LT(((z * z.transpose()) / 40.0 - Eigen::MatrixXd::Identity(3, 3)).norm(), 1e-13);
}

TEST(S2kfLinear, UpdateReproducesClosedFormKalmanFilterForEverySampleSet) {
  std::mt19937_64 rng(1);
  const int n = 4, m = 3;
  for (const SampleSet& set : sample_sets_of_dimension(n)) {
    S2kf filter(set);
    LinearModel model{random_matrix(m, n, rng), random_matrix(m, 1, rng)};
    GaussianXd s2(random_matrix(n, 1, rng), random_spd(n, rng));
    GaussianXd kf = s2;
    const Eigen::MatrixXd r = random_spd(m, rng);
    const Eigen::VectorXd y = random_matrix(m, 1, rng);
    const auto result = filter.update(s2, model, y, r);
    ASSERT_TRUE(result.ok()) << s2kf::to_string(result.status);
    kalman_update(kf, model.h, y - model.offset, r, ObservedMask::Constant(m, true));
    EXPECT_LT(relative_error(s2.mean, kf.mean), 1e-12) << set.kind;
    EXPECT_LT(relative_error(s2.covariance, kf.covariance), 1e-12) << set.kind;
    EXPECT_EQ(result.observed, m);
  }
}

TEST(S2kfLinear, TrackingSizedUpdateMatchesKalmanFilter) {
  // 46 states and 150 measurement rows, as the tracker with 50 markers: Cyy is then large enough
  // that the filter splits its triangular solve (more than 96 rows); with 60 rows hidden it does not.
  std::mt19937_64 rng(5);
  const int n = 46, m = 150;
  for (const SampleSet& set : {s2kf::ukf_sample_set(n), s2kf::compute_lcd_sample_set(n, 301).set}) {
    for (const int hidden : {0, 60}) {
      S2kf filter(set);
      LinearModel model{random_matrix(m, n, rng), random_matrix(m, 1, rng)};
      GaussianXd s2(random_matrix(n, 1, rng), random_spd(n, rng));
      GaussianXd kf = s2;
      const Eigen::MatrixXd r = random_spd(m, rng);
      const Eigen::VectorXd y = random_matrix(m, 1, rng);
      ObservedMask observed = ObservedMask::Constant(m, true);
      for (int i = 0; i < hidden; ++i) observed(2 * i) = false;
      const auto result = filter.update(s2, model, y, r, observed);
      ASSERT_TRUE(result.ok()) << s2kf::to_string(result.status);
      EXPECT_EQ(result.observed, m - hidden);
      kalman_update(kf, model.h, y - model.offset, r, observed);
      EXPECT_LT(relative_error(s2.mean, kf.mean), 1e-9) << set.kind << ", " << hidden << " hidden";
      EXPECT_LT(relative_error(s2.covariance, kf.covariance), 1e-9)
          << set.kind << ", " << hidden << " hidden";
    }
  }
}

TEST(S2kfLinear, SinglePrecisionMomentsMatchKalmanFilterToFloatRounding) {
  // The tracker's setting: Cyy and Cyx summed in float, the rest in double. The result differs
  // from the double-precision update (the option takes effect) by float rounding only: about the
  // unit roundoff of float (6e-8) times the condition of Cyy, which is near 1e6 for these random
  // matrices (measured: 2.4e-5); a wrong formula would miss by order 1.
  std::mt19937_64 rng(7);
  const int n = 46, m = 150;
  for (const SampleSet& set : {s2kf::ukf_sample_set(n), s2kf::compute_lcd_sample_set(n, 301).set}) {
    for (const int hidden : {0, 60}) {
      LinearModel model{random_matrix(m, n, rng), random_matrix(m, 1, rng)};
      const GaussianXd prior(random_matrix(n, 1, rng), random_spd(n, rng));
      GaussianXd single = prior, twice = prior, kf = prior;
      const Eigen::MatrixXd r = random_spd(m, rng);
      const Eigen::VectorXd y = random_matrix(m, 1, rng);
      ObservedMask observed = ObservedMask::Constant(m, true);
      for (int i = 0; i < hidden; ++i) observed(2 * i) = false;
      s2kf::UpdateOptions options;
      options.single_precision_moments = true;
      S2kf filter(set);
      ASSERT_TRUE(filter.update(single, model, y, r, observed, options).ok());
      ASSERT_TRUE(filter.update(twice, model, y, r, observed).ok());
      kalman_update(kf, model.h, y - model.offset, r, observed);
      EXPECT_LT(relative_error(single.mean, kf.mean), 1e-4) << set.kind << ", " << hidden << " hidden";
      EXPECT_LT(relative_error(single.covariance, kf.covariance), 1e-4) << set.kind << ", " << hidden;
      EXPECT_LT(relative_error(twice.mean, kf.mean), 1e-9) << set.kind << ", " << hidden << " hidden";
      EXPECT_GT((single.mean - twice.mean).norm(), 0.0) << set.kind << ", " << hidden << " hidden";
    }
  }
}

TEST(S2kfLinear, SeveralStepsWithPredictionAndAMissingComponentMatchKalmanFilter) {
  std::mt19937_64 rng(2);
  const int n = 5, m = 4;
  S2kf filter(s2kf::random_sample_set(n, 40, 9));
  LinearModel model{random_matrix(m, n, rng), Eigen::VectorXd::Zero(m)};
  const Eigen::MatrixXd a = Eigen::MatrixXd::Identity(n, n) + 0.1 * random_matrix(n, n, rng);
  const Eigen::MatrixXd q = 0.1 * random_spd(n, rng);
  const Eigen::MatrixXd r = random_spd(m, rng);
  GaussianXd s2(Eigen::VectorXd::Zero(n), random_spd(n, rng));
  GaussianXd kf = s2;
  for (int step = 0; step < 6; ++step) {
    ASSERT_EQ(filter.predict_linear(s2, a, q), FilterStatus::ok);
    kf.mean = a * kf.mean;
    kf.covariance = a * kf.covariance * a.transpose() + q;
    ObservedMask observed = ObservedMask::Constant(m, true);
    observed(step % m) = false;  // a different component missing at each step
    Eigen::VectorXd y = random_matrix(m, 1, rng);
    y(step % m) = std::numeric_limits<double>::quiet_NaN();  // never read: it is not observed
    ASSERT_TRUE(filter.update(s2, model, y, r, observed).ok());
    kalman_update(kf, model.h, y, r, observed);
    EXPECT_LT(relative_error(s2.mean, kf.mean), 1e-12) << "step " << step;
    EXPECT_LT(relative_error(s2.covariance, kf.covariance), 1e-12) << "step " << step;
  }
}

TEST(S2kfLinear, SampleBasedPredictionOfALinearModelEqualsClosedForm) {
  std::mt19937_64 rng(3);
  const int n = 3;
  S2kf filter(s2kf::ukf_sample_set(n));
  const Eigen::MatrixXd a = random_matrix(n, n, rng);
  const Eigen::VectorXd b = random_matrix(n, 1, rng);
  const Eigen::MatrixXd q = random_spd(n, rng);
  GaussianXd s(random_matrix(n, 1, rng), random_spd(n, rng));
  GaussianXd expected = s;
  ASSERT_EQ(filter.predict(
                s, [&](const Eigen::MatrixXd& x, Eigen::MatrixXd& out) { out = (a * x).colwise() + b; }, q),
            FilterStatus::ok);
  expected.mean = a * expected.mean + b;
  expected.covariance = a * expected.covariance * a.transpose() + q;
  EXPECT_LT(relative_error(s.mean, expected.mean), 1e-12);
  EXPECT_LT(relative_error(s.covariance, expected.covariance), 1e-12);
}

TEST(S2kfLinear, FixedSizeStateGivesTheSameResultAsDynamic) {
  std::mt19937_64 rng(4);
  s2kf::SmartSamplingKalmanFilter<2> fixed_filter(s2kf::ukf_sample_set(2));
  S2kf dynamic_filter(s2kf::ukf_sample_set(2));
  const Eigen::Matrix2d c = random_spd(2, rng);
  s2kf::Gaussian<double, 2> fixed(Eigen::Vector2d(1, 2), c);
  GaussianXd dynamic(Eigen::VectorXd(fixed.mean), Eigen::MatrixXd(c));
  LinearModel model{random_matrix(1, 2, rng), Eigen::VectorXd::Zero(1)};
  const Eigen::MatrixXd r = Eigen::MatrixXd::Constant(1, 1, 0.3);
  const Eigen::VectorXd y = Eigen::VectorXd::Constant(1, 0.7);
  ASSERT_TRUE(fixed_filter.update(fixed, model, y, r).ok());
  ASSERT_TRUE(dynamic_filter.update(dynamic, model, y, r).ok());
  EXPECT_LT((fixed.mean - dynamic.mean).norm(), 1e-14);
  EXPECT_LT((fixed.covariance - dynamic.covariance).norm(), 1e-14);
  EXPECT_THROW(s2kf::SmartSamplingKalmanFilter<3>(s2kf::ukf_sample_set(2)), s2kf::DimensionError);
}

TEST(S2kfLinear, NisIsTheNormalisedInnovationSquared) {
  S2kf filter(s2kf::ukf_sample_set(2));
  GaussianXd s(Eigen::Vector2d(0, 0), Eigen::Matrix2d::Identity());
  LinearModel model{Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Zero(2)};
  const Eigen::Vector2d y(3, 4);
  const auto result = filter.update(s, model, y, Eigen::MatrixXd::Identity(2, 2));
  // Innovation covariance 2 I: NIS = (9 + 16) / 2.
  EXPECT_NEAR(result.nis, 12.5, 1e-12);
}

TEST(S2kfFailures, NonPositiveDefinitePriorIsReportedAndStateUntouched) {
  S2kf filter(s2kf::ukf_sample_set(2));
  Eigen::Matrix2d c;
  c << 1, 2, 2, 1;  // indefinite
  GaussianXd s(Eigen::Vector2d(1, 1), c);
  const GaussianXd before = s;
  LinearModel model{Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Zero(2)};
  const auto result = filter.update(s, model, Eigen::Vector2d(0, 0), Eigen::MatrixXd::Identity(2, 2));
  EXPECT_EQ(result.status, FilterStatus::prior_not_positive_definite);
  EXPECT_EQ(s.mean, before.mean);
  EXPECT_EQ(s.covariance, before.covariance);
}

TEST(S2kfFailures, NonFiniteModelOutputAndMeasurementAreReported) {
  S2kf filter(s2kf::ukf_sample_set(2));
  GaussianXd s(Eigen::Vector2d(1, 1), Eigen::Matrix2d::Identity());
  const GaussianXd before = s;
  auto nan_model = [](const Eigen::MatrixXd& x, Eigen::MatrixXd& y) {
    y = x;
    y(0, 1) = std::numeric_limits<double>::quiet_NaN();
  };
  EXPECT_EQ(filter.update(s, nan_model, Eigen::Vector2d(0, 0), Eigen::MatrixXd::Identity(2, 2)).status,
            FilterStatus::non_finite_model_output);
  LinearModel model{Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Zero(2)};
  EXPECT_EQ(filter.update(s, model, Eigen::Vector2d(0, INFINITY), Eigen::MatrixXd::Identity(2, 2)).status,
            FilterStatus::non_finite_measurement);
  EXPECT_EQ(s.mean, before.mean);
  EXPECT_EQ(s.covariance, before.covariance);
}

TEST(S2kfFailures, NegativeDefiniteNoiseMakesTheInnovationCovarianceFail) {
  S2kf filter(s2kf::ukf_sample_set(2));
  GaussianXd s(Eigen::Vector2d(1, 1), Eigen::Matrix2d::Identity());
  LinearModel model{Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Zero(2)};
  const auto result = filter.update(s, model, Eigen::Vector2d(0, 0), -5.0 * Eigen::MatrixXd::Identity(2, 2));
  EXPECT_EQ(result.status, FilterStatus::innovation_not_positive_definite);
  EXPECT_EQ(s.mean, Eigen::VectorXd(Eigen::Vector2d(1, 1)));
}

TEST(S2kfFailures, NothingObservedIsANoOp) {
  S2kf filter(s2kf::ukf_sample_set(2));
  GaussianXd s(Eigen::Vector2d(1, 1), Eigen::Matrix2d::Identity());
  LinearModel model{Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Zero(2)};
  const auto result = filter.update(s, model, Eigen::Vector2d(0, 0), Eigen::MatrixXd::Identity(2, 2),
                                    ObservedMask::Constant(2, false));
  EXPECT_EQ(result.status, FilterStatus::nothing_observed);
  EXPECT_EQ(result.observed, 0);
  EXPECT_EQ(s.covariance, Eigen::MatrixXd(Eigen::Matrix2d::Identity()));
}

TEST(S2kfFailures, DimensionMismatchesThrow) {
  S2kf filter(s2kf::ukf_sample_set(2));
  GaussianXd s(Eigen::Vector3d(1, 1, 1), Eigen::Matrix3d::Identity());
  LinearModel model{Eigen::MatrixXd::Identity(3, 3), Eigen::VectorXd::Zero(3)};
  EXPECT_THROW(filter.update(s, model, Eigen::Vector3d(0, 0, 0), Eigen::MatrixXd::Identity(3, 3)),
               s2kf::DimensionError);
  GaussianXd s2(Eigen::Vector2d(1, 1), Eigen::Matrix2d::Identity());
  EXPECT_THROW(filter.update(s2, model, Eigen::Vector2d(0, 0), Eigen::MatrixXd::Identity(3, 3)),
               s2kf::DimensionError);
  EXPECT_THROW(filter.predict_random_walk(s2, Eigen::MatrixXd::Identity(3, 3)), s2kf::DimensionError);
}

TEST(S2kfGating, OutlierBeyondTheChiSquareQuantileIsRejected) {
  S2kf filter(s2kf::ukf_sample_set(2));
  GaussianXd s(Eigen::Vector2d(0, 0), Eigen::Matrix2d::Identity());
  LinearModel model{Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Zero(2)};
  s2kf::UpdateOptions gate;
  gate.gate_probability = 0.99;
  // NIS = 2 * 10^2 / 2 = 100 >> chi2_0.99(2) = 9.21.
  auto result = filter.update(s, model, Eigen::Vector2d(10, 10), Eigen::MatrixXd::Identity(2, 2), gate);
  EXPECT_EQ(result.status, FilterStatus::gated);
  EXPECT_NEAR(result.nis, 100.0, 1e-9);
  EXPECT_EQ(s.mean, Eigen::VectorXd(Eigen::Vector2d(0, 0)));
  // NIS = 2 * 2^2 / 2 = 4 < 9.21: accepted.
  result = filter.update(s, model, Eigen::Vector2d(2, 2), Eigen::MatrixXd::Identity(2, 2), gate);
  EXPECT_TRUE(result.ok());
  EXPECT_NEAR(s.mean(0), 1.0, 1e-12);
}

// Three sensors of the same 3-D state, one block each: y = [x; x; x] + v. A block whose innovation
// is improbable under its own predicted covariance (prior + noise) is left out, and the result is
// exactly the closed-form Kalman update on the other blocks.
struct ThreeSensors {
  GaussianXd prior{Eigen::Vector3d(1, -2, 0.5), Eigen::Matrix3d::Identity() * 4.0};
  LinearModel model{(Eigen::MatrixXd(9, 3) << Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Identity(),
                     Eigen::Matrix3d::Identity())
                        .finished(),
                    Eigen::VectorXd::Zero(9)};
  Eigen::MatrixXd r = Eigen::MatrixXd::Identity(9, 9);
  s2kf::UpdateOptions options() const {
    s2kf::UpdateOptions o;
    o.block_size = 3;
    o.block_gate_probability = 0.9999;  // chi2_3 quantile 21.1
    return o;
  }
};

TEST(S2kfBlockGating, AnOutlyingBlockIsLeftOutAndTheRestIsTheKalmanUpdate) {
  ThreeSensors t;
  Eigen::VectorXd y(9);
  y << 1.5, -1.0, 0.0, 0.5, -2.5, 1.0, 40.0, 30.0, -20.0;  // sensor 2 is 40 SDs off
  for (const SampleSet& set : {s2kf::ukf_sample_set(3), s2kf::compute_lcd_sample_set(3, 31).set}) {
    GaussianXd s = t.prior;
    S2kf filter(set);
    const s2kf::UpdateResult result = filter.update(s, t.model, y, t.r, t.options());
    ASSERT_TRUE(result.ok());
    EXPECT_EQ(result.rejected_blocks, 1);
    ASSERT_EQ(filter.rejected_blocks().size(), 1u);
    EXPECT_EQ(filter.rejected_blocks()[0], 2);
    EXPECT_EQ(result.observed, 6);
    GaussianXd expected = t.prior;
    ObservedMask first_two = ObservedMask::Constant(9, true);
    first_two.tail(3).setConstant(false);
    kalman_update(expected, t.model.h, y, t.r, first_two);
    EXPECT_LT(relative_error(s.mean, expected.mean), 1e-10) << set.kind;
    EXPECT_LT(relative_error(s.covariance, expected.covariance), 1e-10) << set.kind;
  }
}

TEST(S2kfBlockGating, AnOutlyingMiddleBlockIsCutOutOfTheMomentsInEitherPrecision) {
  // The gate reads the blocks' covariances off Cyy and removes a rejected block's rows and columns
  // in place: with the middle block out (and one component of the last hidden), the kept rows move
  // up, and the result must still be the Kalman update on exactly the kept components.
  ThreeSensors t;
  Eigen::VectorXd y(9);
  y << 1.5, -1.0, 0.0, -30.0, 45.0, 25.0, 2.0, -3.0, 1.5;  // sensor 1 is far off
  ObservedMask observed = ObservedMask::Constant(9, true);
  observed(7) = false;
  for (const bool single : {false, true}) {
    for (const SampleSet& set : {s2kf::ukf_sample_set(3), s2kf::compute_lcd_sample_set(3, 31).set}) {
      GaussianXd s = t.prior, expected = t.prior;
      s2kf::UpdateOptions options = t.options();
      options.single_precision_moments = single;
      S2kf filter(set);
      const s2kf::UpdateResult result = filter.update(s, t.model, y, t.r, observed, options);
      ASSERT_TRUE(result.ok());
      ASSERT_EQ(filter.rejected_blocks().size(), 1u);
      EXPECT_EQ(filter.rejected_blocks()[0], 1);
      EXPECT_EQ(result.observed, 5);
      ObservedMask kept = observed;
      kept.segment(3, 3).setConstant(false);
      kalman_update(expected, t.model.h, y, t.r, kept);
      const double tolerance = single ? 1e-5 : 1e-10;
      EXPECT_LT(relative_error(s.mean, expected.mean), tolerance) << set.kind << (single ? " single" : "");
      EXPECT_LT(relative_error(s.covariance, expected.covariance), tolerance) << set.kind;
    }
  }
}

TEST(S2kfBlockGating, ConsistentBlocksAreAllUsed) {
  ThreeSensors t;
  Eigen::VectorXd y(9);
  y << 1.5, -1.0, 0.0, 0.5, -2.5, 1.0, 2.0, -3.0, 1.5;  // every block within 3 SDs
  GaussianXd s = t.prior, expected = t.prior;
  S2kf filter(s2kf::ukf_sample_set(3));
  const s2kf::UpdateResult result = filter.update(s, t.model, y, t.r, t.options());
  EXPECT_EQ(result.rejected_blocks, 0);
  EXPECT_EQ(result.observed, 9);
  kalman_update(expected, t.model.h, y, t.r, ObservedMask::Constant(9, true));
  EXPECT_LT(relative_error(s.mean, expected.mean), 1e-10);
}

TEST(S2kfBlockGating, WhenMostBlocksDisagreeThePredictionIsOffAndNoneIsLeftOut) {
  ThreeSensors t;
  Eigen::VectorXd y(9);
  y << 41.0, 30.0, -20.0, 40.0, 30.5, -20.0, 40.0, 30.0, -19.5;  // all three far: the prior is wrong
  GaussianXd s = t.prior, expected = t.prior;
  S2kf filter(s2kf::ukf_sample_set(3));
  const s2kf::UpdateResult result = filter.update(s, t.model, y, t.r, t.options());
  EXPECT_EQ(result.rejected_blocks, 0);
  kalman_update(expected, t.model.h, y, t.r, ObservedMask::Constant(9, true));
  EXPECT_LT(relative_error(s.mean, expected.mean), 1e-10);
}

TEST(S2kfBlockGating, AHiddenComponentShrinksItsBlockAndBadBlockSizesThrow) {
  ThreeSensors t;
  Eigen::VectorXd y(9);
  y << 1.5, -1.0, 0.0, 0.5, -2.5, 1.0, 40.0, 0.0, 0.0;
  ObservedMask observed = ObservedMask::Constant(9, true);
  observed.tail(2).setConstant(false);  // sensor 2 shows only its x, 40 SDs off: 1 degree of freedom
  GaussianXd s = t.prior;
  S2kf filter(s2kf::ukf_sample_set(3));
  EXPECT_EQ(filter.update(s, t.model, y, t.r, observed, t.options()).rejected_blocks, 1);
  s2kf::UpdateOptions bad = t.options();
  bad.block_size = 4;  // does not divide 9
  EXPECT_THROW(filter.update(s, t.model, y, t.r, bad), s2kf::DimensionError);
}

TEST(ChiSquare, QuantilesMatchTabulatedValues) {
  EXPECT_NEAR(s2kf::chi_square_quantile(0.95, 1), 3.841458820694124, 1e-9);
  EXPECT_NEAR(s2kf::chi_square_quantile(0.99, 3), 11.344866730144373, 1e-9);
  EXPECT_NEAR(s2kf::chi_square_quantile(0.5, 2), 2 * std::log(2.0), 1e-10);  // exponential median
  EXPECT_NEAR(s2kf::chi_square_quantile(0.95, 10), 18.307038053275146, 1e-8);
  EXPECT_NEAR(s2kf::chi_square_quantile(0.99, 100), 135.807, 1e-3);
  EXPECT_NEAR(s2kf::chi_square_cdf(3.841458820694124, 1), 0.95, 1e-12);
  EXPECT_THROW(s2kf::chi_square_quantile(1.5, 2), std::invalid_argument);
}

TEST(S2kfIterated, LinearModelGivesTheKalmanResultForAnyNumberOfPasses) {
  std::mt19937_64 rng(5);
  const int n = 3, m = 2;
  S2kf filter(s2kf::random_sample_set(n, 30, 1));
  LinearModel model{random_matrix(m, n, rng), random_matrix(m, 1, rng)};
  const Eigen::MatrixXd r = random_spd(m, rng);
  const Eigen::VectorXd y = random_matrix(m, 1, rng);
  GaussianXd kf(random_matrix(n, 1, rng), random_spd(n, rng));
  GaussianXd iterated = kf;
  s2kf::UpdateOptions options;
  options.iterations = 4;
  ASSERT_TRUE(filter.update(iterated, model, y, r, options).ok());
  kalman_update(kf, model.h, y - model.offset, r, ObservedMask::Constant(m, true));
  EXPECT_LT(relative_error(iterated.mean, kf.mean), 1e-10);
  EXPECT_LT(relative_error(iterated.covariance, kf.covariance), 1e-10);
}

// A model with evaluate_symmetric: it records what the update handed it and evaluates the same
// cubic as the plain callable, from the mean and the half deviations alone.
struct SymmetricCube {
  int calls = 0;
  Eigen::VectorXd mean;
  void operator()(const Eigen::MatrixXd& x, Eigen::MatrixXd& out) const { out = x.array().cube().matrix(); }
  void evaluate_symmetric(const Eigen::MatrixXd& states, const Eigen::Ref<const Eigen::VectorXd>& m,
                          const Eigen::MatrixXd& half, Eigen::Index origin, Eigen::MatrixXd& out) {
    ++calls;
    mean = m;
    Eigen::MatrixXd rebuilt(m.size(), origin + 2 * half.cols());
    rebuilt.leftCols(origin).colwise() = m;
    rebuilt.middleCols(origin, half.cols()) = half.colwise() + m;
    rebuilt.rightCols(half.cols()) = (-half).colwise() + m;
    EXPECT_LT((rebuilt - states).cwiseAbs().maxCoeff(), 1e-12);  // the columns the generic model gets
    out = rebuilt.array().cube().matrix();
  }
};

TEST(S2kfSymmetricModels, TheUpdateHandsASymmetricSetToEvaluateSymmetricAsMeanAndHalfDeviations) {
  std::mt19937_64 rng(9);
  const int n = 3;
  const Eigen::MatrixXd r = 0.5 * Eigen::MatrixXd::Identity(n, n);
  const Eigen::VectorXd y = random_matrix(n, 1, rng);
  const GaussianXd prior(random_matrix(n, 1, rng), random_spd(n, rng));
  const auto cube = [](const Eigen::MatrixXd& x, Eigen::MatrixXd& out) { out = x.array().cube().matrix(); };
  // The LCD sets are symmetric (with the origin and without); a random set is not: the plain callable runs.
  for (const auto& [set, symmetric_set] : {std::pair{s2kf::compute_lcd_sample_set(n, 31).set, true},
                                           std::pair{s2kf::compute_lcd_sample_set(n, 30).set, true},
                                           std::pair{s2kf::random_sample_set(n, 30, 2), false}}) {
    S2kf plain_filter(set), symmetric_filter(set);
    GaussianXd plain = prior, symmetric = prior;
    SymmetricCube model;
    ASSERT_TRUE(plain_filter.update(plain, cube, y, r).ok());
    ASSERT_TRUE(symmetric_filter.update(symmetric, model, y, r).ok());
    EXPECT_EQ(model.calls, symmetric_set ? 1 : 0);
    if (model.calls > 0) {
      EXPECT_EQ(model.mean, prior.mean);
    }
    EXPECT_LT(relative_error(symmetric.mean, plain.mean), 1e-12);
    EXPECT_LT(relative_error(symmetric.covariance, plain.covariance), 1e-12);
    // The iterated update works on all deviations and calls the plain callable.
    model.calls = 0;
    s2kf::UpdateOptions options;
    options.iterations = 3;
    GaussianXd iterated = prior;
    ASSERT_TRUE(symmetric_filter.update(iterated, model, y, r, options).ok());
    EXPECT_EQ(model.calls, 0);
  }
}

// y = x^3 + v with an informative measurement: the exact posterior mean comes from 1-D quadrature.
TEST(S2kfIterated, PosteriorLinearisationMovesTheMeanCloserToTheExactPosterior) {
  const double prior_mean = 1.0, prior_sd = 0.5, noise_sd = 0.05, y = 2.0;
  auto density = [&](double x) {
    const double a = (x - prior_mean) / prior_sd, b = (y - x * x * x) / noise_sd;
    return std::exp(-0.5 * (a * a + b * b));
  };
  double z = 0, first = 0;
  for (int i = 0; i <= 400000; ++i) {
    const double x = -2.0 + 6.0 * i / 400000.0, w = density(x);
    z += w;
    first += w * x;
  }
  const double exact_mean = first / z;
  auto cube = [](const Eigen::MatrixXd& x, Eigen::MatrixXd& out) { out = x.array().cube().matrix(); };
  S2kf filter(s2kf::random_sample_set(1, 201, 7));
  const Eigen::MatrixXd r = Eigen::MatrixXd::Constant(1, 1, noise_sd * noise_sd);
  const Eigen::VectorXd yv = Eigen::VectorXd::Constant(1, y);
  GaussianXd single(Eigen::VectorXd::Constant(1, prior_mean),
                    Eigen::MatrixXd::Constant(1, 1, prior_sd * prior_sd));
  GaussianXd iterated = single;
  s2kf::UpdateOptions options;
  options.iterations = 8;
  ASSERT_TRUE(filter.update(single, cube, yv, r).ok());
  ASSERT_TRUE(filter.update(iterated, cube, yv, r, options).ok());
  const double single_error = std::abs(single.mean(0) - exact_mean);
  const double iterated_error = std::abs(iterated.mean(0) - exact_mean);
  EXPECT_LT(iterated_error, 0.25 * single_error);
  EXPECT_LT(iterated_error, 0.01);
}

}  // namespace
