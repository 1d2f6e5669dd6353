// The information-form update (UpdateOptions::information_form) against the closed-form Kalman
// filter and the ordinary S2KF update: equal where the innovation covariance is G G^T + D with D
// block-diagonal (linear models; nonlinear parts confined to one block), different only by the
// cross-block correlation of nonlinear parts, and never taken where it would not be exact.
#include <s2kf/core/lcd_sample_set.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>

#include "kalman_reference.hpp"

#include <gtest/gtest.h>
#include <Eigen/LU>

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

namespace {

using s2kf::GaussianXd;
using s2kf::ObservedMask;
using s2kf::S2kf;
using s2kf::SampleSet;
using s2kf::UpdateOptions;

using s2kf::test::kalman_update;
using s2kf::test::LinearModel;
using s2kf::test::random_matrix;
using s2kf::test::random_spd;
using s2kf::test::relative_error;

// A random noise covariance that couples the components of a block but not the blocks.
Eigen::MatrixXd block_diagonal_spd(int m, int block, std::mt19937_64& rng) {
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(m, m);
  for (int k = 0; k < m; k += block) r.block(k, k, block, block) = random_spd(block, rng);
  return r;
}

UpdateOptions information_form(int block_size) {
  UpdateOptions options;
  options.information_form = true;
  options.block_size = block_size;
  return options;
}

// Blocks of three components; the blocks listed in `nonlinear` add a smooth nonlinear function
// of the whole state (so their nonlinear parts are correlated with each other), the rest are
// linear in the state.
struct PartlyNonlinearModel {
  Eigen::MatrixXd h;
  std::vector<int> nonlinear;
  void operator()(const Eigen::MatrixXd& x, Eigen::MatrixXd& y) const {
    y = h * x;
    for (const int block : nonlinear)
      for (Eigen::Index i = 0; i < x.cols(); ++i) {
        const double a = x(0, i), b = x(1, i);
        y(3 * block, i) += 0.8 * std::sin(a * b) + 0.3 * a * a;
        y(3 * block + 1, i) += 0.5 * a * b;
        y(3 * block + 2, i) += 0.4 * std::cos(a + b) * b;
      }
  }
};

// One update of `prior` with the information form and the block gate (markers of 3 components,
// `groups` if given): it must leave out exactly marker `block`, and the state must be the Kalman
// update on the other observed components, to 1e-10 in double and to float rounding (1e-5) with
// single-precision moments.
void expect_the_gate_leaves_out(Eigen::Index block, const LinearModel& model, const GaussianXd& prior,
                                const Eigen::VectorXd& y, const Eigen::MatrixXd& r,
                                const ObservedMask& observed, const std::vector<int>* groups, bool single) {
  GaussianXd s = prior, expected = prior;
  UpdateOptions options = information_form(3);
  options.information_groups = groups;
  options.block_gate_probability = 0.9999;
  options.single_precision_moments = single;
  S2kf filter(s2kf::compute_lcd_sample_set(static_cast<int>(prior.mean.size()), 31).set);
  const s2kf::UpdateResult result = filter.update(s, model, y, r, observed, options);
  ASSERT_TRUE(result.ok());
  ASSERT_EQ(filter.rejected_blocks().size(), 1u);
  EXPECT_EQ(filter.rejected_blocks()[0], block);
  ObservedMask kept = observed;
  kept.segment(3 * block, 3).setConstant(false);
  EXPECT_EQ(result.observed, kept.count());
  kalman_update(expected, model.h, y, r, kept);
  const double tolerance = single ? 1e-5 : 1e-10;
  EXPECT_LT(relative_error(s.mean, expected.mean), tolerance) << (single ? "single" : "double");
  EXPECT_LT(relative_error(s.covariance, expected.covariance), tolerance) << (single ? "single" : "double");
}

TEST(InformationForm, LinearModelsGiveTheKalmanUpdateAtTheTrackersSize) {
  // 46 states and 50 blocks of 3, as the tracker with 50 markers; with 60 components hidden every
  // other one, many blocks keep one or two of their components.
  std::mt19937_64 rng(21);
  const int n = 46, m = 150;
  for (const SampleSet& set : {s2kf::ukf_sample_set(n), s2kf::compute_lcd_sample_set(n, 301).set}) {
    for (const int hidden : {0, 60}) {
      LinearModel model{random_matrix(m, n, rng), random_matrix(m, 1, rng)};
      const GaussianXd prior(random_matrix(n, 1, rng), random_spd(n, rng));
      const Eigen::MatrixXd r = block_diagonal_spd(m, 3, rng);
      const Eigen::VectorXd y = random_matrix(m, 1, rng);
      ObservedMask observed = ObservedMask::Constant(m, true);
      for (int i = 0; i < hidden; ++i) observed(2 * i) = false;
      GaussianXd information = prior, ordinary = prior, kf = prior;
      S2kf filter(set);
      const s2kf::UpdateResult a = filter.update(information, model, y, r, observed, information_form(3));
      const s2kf::UpdateResult b = filter.update(ordinary, model, y, r, observed);
      ASSERT_TRUE(a.ok() && b.ok());
      kalman_update(kf, model.h, y - model.offset, r, observed);
      EXPECT_LT(relative_error(information.mean, kf.mean), 1e-9) << set.kind << ", " << hidden << " hidden";
      EXPECT_LT(relative_error(information.covariance, kf.covariance), 1e-9) << set.kind << ", " << hidden;
      EXPECT_NEAR(a.nis, b.nis, 1e-8 * b.nis) << set.kind << ", " << hidden << " hidden";
      EXPECT_EQ(a.observed, m - hidden);
    }
  }
}

TEST(InformationForm, SinglePrecisionMomentsStayWithinFloatRoundingOfTheKalmanUpdate) {
  // Each block's unexplained spread is C_b - G_b G_b^T, a difference of numbers of the size of the
  // predicted spread (about 5e3 here, float rounding 6e-8 of it), set against R = 2: measured
  // 1.9e-4 relative to the Kalman update; the double update is within 1e-9, a wrong formula
  // misses by order 1.
  std::mt19937_64 rng(22);
  const int n = 46, m = 150;
  const SampleSet set = s2kf::compute_lcd_sample_set(n, 301).set;
  LinearModel model{random_matrix(m, n, rng), random_matrix(m, 1, rng)};
  const GaussianXd prior(random_matrix(n, 1, rng), random_spd(n, rng));
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(m, m) * 2.0;
  const Eigen::VectorXd y = random_matrix(m, 1, rng);
  GaussianXd information = prior, twice = prior, kf = prior;
  UpdateOptions options = information_form(3);
  options.single_precision_moments = true;
  S2kf filter(set);
  ASSERT_TRUE(filter.update(information, model, y, r, options).ok());
  ASSERT_TRUE(filter.update(twice, model, y, r, information_form(3)).ok());
  kalman_update(kf, model.h, y - model.offset, r, ObservedMask::Constant(m, true));
  EXPECT_LT(relative_error(information.mean, kf.mean), 1e-3);
  EXPECT_LT(relative_error(information.covariance, kf.covariance), 1e-3);
  EXPECT_LT(relative_error(twice.mean, kf.mean), 1e-9);
  EXPECT_GT((information.mean - twice.mean).norm(), 0.0);  // the option took effect
}

TEST(InformationForm, ANonlinearityConfinedToOneBlockGivesTheOrdinaryUpdate) {
  // The nonlinear parts of a single block are correlated with nothing else, so the ordinary
  // update's Cyy is exactly G G^T + D with D block-diagonal.
  std::mt19937_64 rng(23);
  const int n = 4, m = 12;
  for (const SampleSet& set : {s2kf::ukf_sample_set(n), s2kf::compute_lcd_sample_set(n, 41).set}) {
    PartlyNonlinearModel model{random_matrix(m, n, rng), {1}};
    const GaussianXd prior(random_matrix(n, 1, rng) * 0.3, random_spd(n, rng) * 0.2);
    const Eigen::MatrixXd r = block_diagonal_spd(m, 3, rng) * 0.1;
    const Eigen::VectorXd y = random_matrix(m, 1, rng);
    GaussianXd information = prior, ordinary = prior;
    S2kf filter(set);
    const s2kf::UpdateResult a = filter.update(information, model, y, r, information_form(3));
    const s2kf::UpdateResult b = filter.update(ordinary, model, y, r);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_LT(relative_error(information.mean, ordinary.mean), 1e-10) << set.kind;
    EXPECT_LT(relative_error(information.covariance, ordinary.covariance), 1e-10) << set.kind;
    EXPECT_NEAR(a.nis, b.nis, 1e-9 * b.nis) << set.kind;
  }
}

TEST(InformationForm, OneBlockForTheWholeMeasurementIsTheOrdinaryUpdateOfAnyModel) {
  // With a single block D holds every nonlinear correlation, and the update is the ordinary one
  // by the Woodbury identity; 6 components use the small blocks, 12 the general path.
  std::mt19937_64 rng(24);
  const int n = 4;
  for (const int m : {6, 12}) {
    PartlyNonlinearModel model{random_matrix(m, n, rng), {0, 1}};
    if (m == 12) model.nonlinear = {0, 1, 2, 3};
    const GaussianXd prior(random_matrix(n, 1, rng) * 0.3, random_spd(n, rng) * 0.3);
    const Eigen::MatrixXd r = random_spd(m, rng) * 0.1;
    const Eigen::VectorXd y = random_matrix(m, 1, rng);
    GaussianXd information = prior, ordinary = prior;
    S2kf filter(s2kf::compute_lcd_sample_set(n, 41).set);
    ASSERT_TRUE(filter.update(information, model, y, r, information_form(m)).ok());
    ASSERT_TRUE(filter.update(ordinary, model, y, r).ok());
    EXPECT_LT(relative_error(information.mean, ordinary.mean), 1e-10) << m;
    EXPECT_LT(relative_error(information.covariance, ordinary.covariance), 1e-10) << m;
  }
}

TEST(InformationForm, WhatItLeavesOutIsTheCrossBlockCorrelationOfNonlinearParts) {
  // Two blocks share one nonlinearity: the information form treats their nonlinear parts as
  // independent, so it differs from the ordinary update, by a little; with a narrow prior (where
  // the model is nearly linear over the samples) by much less.
  std::mt19937_64 rng(25);
  const int n = 4, m = 9;
  PartlyNonlinearModel model{random_matrix(m, n, rng), {0, 2}};
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(m, m) * 0.5;
  const Eigen::VectorXd y = random_matrix(m, 1, rng);
  const Eigen::VectorXd mean = random_matrix(n, 1, rng) * 0.3;
  const Eigen::MatrixXd shape = random_spd(n, rng);
  double previous = 0;
  for (const double scale : {0.3, 0.003}) {
    const GaussianXd prior(mean, shape * scale);
    GaussianXd information = prior, ordinary = prior;
    S2kf filter(s2kf::compute_lcd_sample_set(n, 41).set);
    ASSERT_TRUE(filter.update(information, model, y, r, information_form(3)).ok());
    ASSERT_TRUE(filter.update(ordinary, model, y, r).ok());
    const double difference = relative_error(information.mean, ordinary.mean);
    if (scale == 0.3) {
      EXPECT_GT(difference, 1e-6);  // the option took effect (measured 0.07)
      EXPECT_LT(difference, 0.2);
    } else {
      EXPECT_LT(difference, 1e-3 * previous);  // measured 8e-5 of it
    }
    previous = difference;
  }
}

TEST(InformationForm, GroupsKeepTheCorrelationOfNonlinearPartsWithinThemselves) {
  // Blocks that share one nonlinearity put in one group: D then holds their correlation, and the
  // update is the ordinary one, while a group per block leaves it out and is not. 9 components
  // in a group take the general path (a rank update and an in-place factor per group), 6 the
  // small blocks'; in single precision the sums round to float (the same bound as the Kalman
  // update's with single-precision moments).
  std::mt19937_64 rng(29);
  const int n = 4;
  for (const int shared : {2, 3}) {
    const int m = 3 * (shared + 3);
    PartlyNonlinearModel model{random_matrix(m, n, rng), {}};
    for (int block = 0; block < shared; ++block) model.nonlinear.push_back(block);
    std::vector<int> groups(static_cast<std::size_t>(m), 7);
    std::fill(groups.begin(), groups.begin() + 3 * shared, 2);  // ids need not start at 0
    const GaussianXd prior(random_matrix(n, 1, rng) * 0.3, random_spd(n, rng) * 0.3);
    const Eigen::MatrixXd r = block_diagonal_spd(m, 3, rng) * 0.5;
    const Eigen::VectorXd y = random_matrix(m, 1, rng);
    for (const bool single : {false, true}) {
      GaussianXd grouped = prior, per_block = prior, ordinary = prior;
      S2kf filter(s2kf::compute_lcd_sample_set(n, 41).set);
      UpdateOptions options = information_form(3), plain;
      options.single_precision_moments = plain.single_precision_moments = single;
      ASSERT_TRUE(filter.update(per_block, model, y, r, options).ok());
      options.information_groups = &groups;
      const s2kf::UpdateResult a = filter.update(grouped, model, y, r, options);
      const s2kf::UpdateResult b = filter.update(ordinary, model, y, r, plain);
      ASSERT_TRUE(a.ok() && b.ok());
      // Measured: 5e-16 and 2e-15 in double, 4e-7 and 5e-7 in single; a group per block is
      // 0.02 and 0.009 off.
      const double tolerance = single ? 1e-5 : 1e-10;
      EXPECT_LT(relative_error(grouped.mean, ordinary.mean), tolerance) << shared << ", single " << single;
      EXPECT_LT(relative_error(grouped.covariance, ordinary.covariance), tolerance)
          << shared << ", " << single;
      EXPECT_NEAR(a.nis, b.nis, tolerance * b.nis) << shared << ", single " << single;
      EXPECT_GT(relative_error(per_block.mean, ordinary.mean), 1e-3) << shared << ", single " << single;
    }
  }
}

TEST(InformationForm, TheBlockGateKeepsEachGroupWhole) {
  // A linear model with groups of four sensors' blocks (12 components, the general path), one
  // sensor far off and one component hidden: the gate leaves out that sensor's block, the
  // compacted groups keep the rest of their covariance, and the result is the Kalman update on
  // the kept components.
  std::mt19937_64 rng(30);
  const int n = 3, m = 24;
  Eigen::MatrixXd h(m, n);
  for (int k = 0; k < m; k += 3)
    h.middleRows(k, 3) = Eigen::Matrix3d::Identity() + 0.3 * random_matrix(3, 3, rng);
  LinearModel model{h, Eigen::VectorXd::Zero(m)};
  const GaussianXd prior{Eigen::Vector3d(1, -2, 0.5), Eigen::Matrix3d::Identity() * 4.0};
  const Eigen::MatrixXd r = block_diagonal_spd(m, 3, rng);
  Eigen::VectorXd y = h * prior.mean + 0.5 * random_matrix(m, 1, rng);
  y.segment(6, 3) += Eigen::Vector3d(-40, 55, 30);  // block 2, inside the first group
  ObservedMask observed = ObservedMask::Constant(m, true);
  observed(13) = false;
  std::vector<int> groups(static_cast<std::size_t>(m), 0);
  std::fill(groups.begin() + 12, groups.end(), 1);
  for (const bool single : {false, true})
    expect_the_gate_leaves_out(2, model, prior, y, r, observed, &groups, single);
}

TEST(InformationForm, GroupsThatDoNotFitTheMeasurementAreRefused) {
  std::mt19937_64 rng(31);
  const int n = 3, m = 9;
  LinearModel model{random_matrix(m, n, rng), Eigen::VectorXd::Zero(m)};
  const GaussianXd prior(Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Identity(n, n));
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(m, m);
  const Eigen::VectorXd y = random_matrix(m, 1, rng);
  const std::vector<std::vector<int>> wrong = {
      {0, 0, 0, 1, 1, 1},           // too few
      {1, 1, 1, 0, 0, 0, 2, 2, 2},  // decreasing
      {0, 0, 0, 0, 1, 1, 1, 1, 1},  // the second block in two groups
  };
  for (const std::vector<int>& groups : wrong) {
    GaussianXd s = prior;
    UpdateOptions options = information_form(3);
    options.information_groups = &groups;
    S2kf filter(s2kf::compute_lcd_sample_set(n, 31).set);
    EXPECT_THROW(filter.update(s, model, y, r, options), s2kf::DimensionError) << groups.size();
    EXPECT_EQ(s.mean, prior.mean);
  }
}

TEST(InformationForm, TheOrdinaryUpdateRunsWhereTheInformationFormWouldNotBeExact) {
  // Cross-block nonlinearity (where the two forms differ), then: R coupling two blocks, a set
  // with a negative weight, an iterated update. Each must give exactly the ordinary result.
  std::mt19937_64 rng(26);
  const int n = 4, m = 9;
  PartlyNonlinearModel model{random_matrix(m, n, rng), {0, 2}};
  const GaussianXd prior(random_matrix(n, 1, rng) * 0.3, random_spd(n, rng) * 0.3);
  const Eigen::VectorXd y = random_matrix(m, 1, rng);
  Eigen::MatrixXd coupled = Eigen::MatrixXd::Identity(m, m) * 0.5;
  coupled(4, 0) = coupled(0, 4) = 0.1;
  const SampleSet negative = s2kf::ukf_sample_set(n, -1.0);
  ASSERT_LT(negative.weights.minCoeff(), 0.0);
  struct Case {
    const char* what;
    SampleSet set;
    Eigen::MatrixXd r;
    int iterations;
  };
  const Eigen::MatrixXd diagonal = Eigen::MatrixXd::Identity(m, m) * 0.5;
  for (const Case& c : {Case{"coupled R", s2kf::compute_lcd_sample_set(n, 41).set, coupled, 1},
                        Case{"negative weight", negative, diagonal, 1},
                        Case{"iterated", s2kf::compute_lcd_sample_set(n, 41).set, diagonal, 3}}) {
    GaussianXd information = prior, ordinary = prior;
    S2kf filter(c.set);
    UpdateOptions options = information_form(3), plain;
    options.iterations = plain.iterations = c.iterations;
    ASSERT_TRUE(filter.update(information, model, y, c.r, options).ok()) << c.what;
    ASSERT_TRUE(filter.update(ordinary, model, y, c.r, plain).ok()) << c.what;
    EXPECT_EQ(information.mean, ordinary.mean) << c.what;
    EXPECT_EQ(information.covariance, ordinary.covariance) << c.what;
  }
}

TEST(InformationForm, ANonlinearityBeyondTheLimitFallsBackToTheOrdinaryUpdate) {
  // The same cross-block nonlinearity: the unexplained spread is far above 1e-6 of R, so with that
  // limit the update is exactly the ordinary one (its moments come from the same deviations, in
  // either precision), and with no limit it is not.
  std::mt19937_64 rng(28);
  const int n = 4, m = 9;
  PartlyNonlinearModel model{random_matrix(m, n, rng), {0, 2}};
  const GaussianXd prior(random_matrix(n, 1, rng) * 0.3, random_spd(n, rng) * 0.3);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(m, m) * 0.5;
  const Eigen::VectorXd y = random_matrix(m, 1, rng);
  for (const bool single : {false, true}) {
    GaussianXd limited = prior, unlimited = prior, ordinary = prior;
    S2kf filter(s2kf::compute_lcd_sample_set(n, 41).set);
    UpdateOptions options = information_form(3), plain;
    options.single_precision_moments = plain.single_precision_moments = single;
    ASSERT_TRUE(filter.update(unlimited, model, y, r, options).ok());
    options.information_form_max_nonlinearity = 1e-6;
    ASSERT_TRUE(filter.update(limited, model, y, r, options).ok());
    ASSERT_TRUE(filter.update(ordinary, model, y, r, plain).ok());
    EXPECT_EQ(limited.mean, ordinary.mean) << single;
    EXPECT_EQ(limited.covariance, ordinary.covariance) << single;
    EXPECT_GT((unlimited.mean - ordinary.mean).norm(), 1e-8) << single;
  }
}

TEST(InformationForm, OneNonlinearBlockAloneDoesNotMakeItFallBack) {
  // The cross-block terms the form leaves out are bounded by sqrt(Omega_ii Omega_jj): with one
  // block nonlinear and the others linear they vanish, so even a limit of 1e-6 keeps the
  // information form (its result is not the ordinary update's bit for bit, but equal to it to
  // rounding), while a second nonlinear block sends the update to the ordinary form (bit for bit).
  std::mt19937_64 rng(32);
  const int n = 4, m = 9;
  const GaussianXd prior(random_matrix(n, 1, rng) * 0.3, random_spd(n, rng) * 0.3);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(m, m) * 0.5;
  const Eigen::VectorXd y = random_matrix(m, 1, rng);
  const Eigen::MatrixXd h = random_matrix(m, n, rng);
  for (const bool two : {false, true}) {
    PartlyNonlinearModel model{h, two ? std::vector<int>{0, 2} : std::vector<int>{1}};
    GaussianXd information = prior, ordinary = prior;
    S2kf filter(s2kf::compute_lcd_sample_set(n, 41).set);
    UpdateOptions options = information_form(3), plain;
    options.information_form_max_nonlinearity = 1e-6;
    ASSERT_TRUE(filter.update(information, model, y, r, options).ok());
    ASSERT_TRUE(filter.update(ordinary, model, y, r, plain).ok());
    if (two) {
      EXPECT_EQ(information.mean, ordinary.mean);
    } else {
      EXPECT_NE(information.mean, ordinary.mean);
      EXPECT_LT(relative_error(information.mean, ordinary.mean), 1e-10);
      EXPECT_LT(relative_error(information.covariance, ordinary.covariance), 1e-10);
    }
  }
}

TEST(InformationForm, TheBlockGateLeavesOutTheOutlyingBlockInEitherPrecision) {
  // Three sensors of one 3-D state, the middle one far off and one component of the last hidden:
  // the result is the Kalman update on the kept components.
  const GaussianXd prior{Eigen::Vector3d(1, -2, 0.5), Eigen::Matrix3d::Identity() * 4.0};
  LinearModel model{(Eigen::MatrixXd(9, 3) << Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Identity(),
                     Eigen::Matrix3d::Identity())
                        .finished(),
                    Eigen::VectorXd::Zero(9)};
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(9, 9);
  Eigen::VectorXd y(9);
  y << 1.5, -1.0, 0.0, -30.0, 45.0, 25.0, 2.0, -3.0, 1.5;
  ObservedMask observed = ObservedMask::Constant(9, true);
  observed(7) = false;
  for (const bool single : {false, true})
    expect_the_gate_leaves_out(1, model, prior, y, r, observed, nullptr, single);
}

TEST(InformationForm, ANoiseBlockThatIsNotPositiveDefiniteIsReportedAndTheStateKept) {
  std::mt19937_64 rng(27);
  const int n = 3, m = 6;
  LinearModel model{random_matrix(m, n, rng), Eigen::VectorXd::Zero(m)};
  const GaussianXd prior(Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Identity(n, n));
  Eigen::MatrixXd r = Eigen::MatrixXd::Identity(m, m);
  r.block(3, 3, 3, 3) = -Eigen::Matrix3d::Identity();
  GaussianXd s = prior;
  S2kf filter(s2kf::compute_lcd_sample_set(n, 31).set);
  const s2kf::UpdateResult result = filter.update(s, model, random_matrix(m, 1, rng), r, information_form(3));
  EXPECT_EQ(result.status, s2kf::FilterStatus::innovation_not_positive_definite);
  EXPECT_EQ(s.mean, prior.mean);
  EXPECT_EQ(s.covariance, prior.covariance);
}

}  // namespace

namespace {

// Blocks whose nonlinear parts are quadratic in states 0 and 1, with the same products in every
// block (as every body part shares the root's orientation).
struct SharedQuadraticModel {
  Eigen::MatrixXd h;  // m x n
  Eigen::MatrixXd c;  // m x 3: the coefficients of x0^2, x0 x1 and x1^2
  void operator()(const Eigen::MatrixXd& x, Eigen::MatrixXd& y) const {
    y = h * x;
    for (Eigen::Index i = 0; i < x.cols(); ++i) {
      const double a = x(0, i), b = x(1, i);
      y.col(i) += c.col(0) * (a * a) + c.col(1) * (a * b) + c.col(2) * (b * b);
    }
  }
};

// A model that gives the update its samples as float deviations from the mean's predictions
// (evaluate_symmetric_deviations, as body::MarkerMeasurementModel does): here `plain`'s predictions
// in double minus the mean's, rounded to float, so that the update's float path and its double
// predictions path see the same model.
template <typename Model>
struct FloatDeviations {
  Model plain;
  int calls = 0;
  void operator()(const Eigen::MatrixXd& x, Eigen::MatrixXd& y) const { plain(x, y); }
  bool evaluate_symmetric_deviations(const Eigen::Ref<const Eigen::VectorXd>& mean,
                                     const Eigen::Ref<const Eigen::MatrixXf>& half, Eigen::Index origin,
                                     Eigen::Ref<Eigen::MatrixXf> deviations,
                                     Eigen::Ref<Eigen::VectorXd> mean_prediction) {
    ++calls;
    const Eigen::MatrixXd h = half.cast<double>();
    Eigen::MatrixXd states(mean.size(), origin + 2 * h.cols());
    states.leftCols(origin).colwise() = mean;
    states.middleCols(origin, h.cols()) = h.colwise() + mean;
    states.rightCols(h.cols()) = (-h).colwise() + mean;
    Eigen::MatrixXd y(deviations.rows(), states.cols()), at_mean(deviations.rows(), 1);
    plain(states, y);
    plain(Eigen::MatrixXd(mean), at_mean);
    deviations = (y.colwise() - at_mean.col(0)).cast<float>();
    mean_prediction = at_mean.col(0);
    return true;
  }
};

}  // namespace

TEST(InformationForm, AModelsFloatDeviationsGiveTheUpdateOfItsPredictions) {
  // The single-precision update of a model that hands over float deviations from its mean
  // prediction (not centred, not weighted: the update centres the moments by the deviations'
  // mean, which nonlinear blocks move away from zero) against the same update of its double
  // predictions: the information form with a large group, hidden components and the block gate,
  // its fallback to the ordinary update, the products of two states, and the square-root gain.
  // Both round in float: within 2e-5; without the centre (c c^T) it misses by 2e-3 to 1e-2.
  std::mt19937_64 rng(43);
  const int n = 8, m = 27;
  PartlyNonlinearModel nonlinear{random_matrix(m, n, rng), {0, 1, 4, 8}};
  const GaussianXd prior(random_matrix(n, 1, rng) * 0.3, random_spd(n, rng) * 0.3);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(m, m) * 0.5;
  const Eigen::VectorXd y = random_matrix(m, 1, rng);
  std::vector<int> groups(m, 0);  // blocks 0-6 one group of 21 components, then two of 3
  for (int i = 21; i < m; ++i) groups[static_cast<std::size_t>(i)] = i < 24 ? 1 : 2;
  const std::vector<int> states = {0, 1};
  ObservedMask hidden = ObservedMask::Constant(m, true);
  hidden.segment(3, 3).setConstant(false);
  hidden(10) = false;
  struct Case {
    const char* what;
    bool information_form;
    double limit;
    const std::vector<int>* products;
    ObservedMask observed;
  };
  const double none = std::numeric_limits<double>::infinity();
  const ObservedMask all = ObservedMask::Constant(m, true);
  for (const Case& c :
       {Case{"information form", true, none, nullptr, all},
        Case{"hidden components", true, none, nullptr, hidden}, Case{"fallback", true, 1e-6, nullptr, hidden},
        Case{"products", true, none, &states, all}, Case{"square-root gain", false, none, nullptr, hidden}}) {
    for (const int samples : {41, 40}) {  // with the origin and without
      UpdateOptions options = information_form(3);
      options.information_form = c.information_form;
      options.information_form_max_nonlinearity = c.limit;
      options.information_groups = &groups;
      options.information_quadratic_states = c.products;
      options.single_precision_moments = true;
      options.block_gate_probability = 0.9999;
      S2kf filter(s2kf::compute_lcd_sample_set(n, samples).set);
      FloatDeviations<PartlyNonlinearModel> model{nonlinear};
      GaussianXd through_float = prior, through_double = prior;
      ASSERT_TRUE(filter.update(through_float, model, y, r, c.observed, options).ok()) << c.what;
      ASSERT_TRUE(filter.update(through_double, nonlinear, y, r, c.observed, options).ok()) << c.what;
      EXPECT_EQ(model.calls, 1) << c.what;
      EXPECT_LT(relative_error(through_float.mean, through_double.mean), 2e-5) << c.what << ", " << samples;
      EXPECT_LT(relative_error(through_float.covariance, through_double.covariance), 2e-5)
          << c.what << ", " << samples;
    }
  }
}

TEST(InformationForm, ASharedQuadraticNonlinearityCarriedAsProductsGivesTheOrdinaryUpdate) {
  // The regression on the state and on the whitened products of states 0 and 1 explains these
  // predictions exactly, so D is R and the information form with the products is the ordinary
  // update to rounding; without them it leaves out the blocks' shared quadratic part.
  std::mt19937_64 rng(41);
  const int n = 5, m = 12;
  SharedQuadraticModel model{random_matrix(m, n, rng), random_matrix(m, 3, rng)};
  const GaussianXd prior(random_matrix(n, 1, rng) * 0.3, random_spd(n, rng) * 0.3);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(m, m) * 0.05;
  const Eigen::VectorXd y = random_matrix(m, 1, rng);
  const std::vector<int> states = {0, 1};
  for (const bool single : {false, true}) {
    S2kf filter(s2kf::compute_lcd_sample_set(n, 41).set);
    GaussianXd with = prior, without = prior, ordinary = prior;
    UpdateOptions options = information_form(3), plain;
    options.single_precision_moments = plain.single_precision_moments = single;
    ASSERT_TRUE(filter.update(ordinary, model, y, r, plain).ok());
    ASSERT_TRUE(filter.update(without, model, y, r, options).ok());
    options.information_quadratic_states = &states;
    const auto result = filter.update(with, model, y, r, options);
    ASSERT_TRUE(result.ok());
    // Sums of both updates, amplified by the small noise: in float 1e-4 (measured 3e-5), in double
    // 1e-8 (measured 2.5e-10 where Clang fuses multiplies and adds, less with GCC).
    const double rounding = single ? 1e-4 : 1e-8;
    EXPECT_LT(relative_error(with.mean, ordinary.mean), rounding) << single;
    EXPECT_LT(relative_error(with.covariance, ordinary.covariance), rounding) << single;
    EXPECT_GT(relative_error(without.mean, ordinary.mean), 100 * rounding) << single;  // measured 1.4
    EXPECT_GT(relative_error(without.covariance, ordinary.covariance), 100 * rounding) << single;  // 0.15
  }
}

TEST(InformationForm, QuadraticStatesThatDoNotFitTheStateAreRefused) {
  std::mt19937_64 rng(43);
  const int n = 4, m = 6;
  const LinearModel model{random_matrix(m, n, rng), Eigen::VectorXd::Zero(m)};
  const GaussianXd prior(random_matrix(n, 1, rng), random_spd(n, rng));
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(m, m);
  const Eigen::VectorXd y = random_matrix(m, 1, rng);
  S2kf filter(s2kf::compute_lcd_sample_set(n, 31).set);
  UpdateOptions options = information_form(3);
  for (const std::vector<int>& states : {std::vector<int>{4}, std::vector<int>{-1}, std::vector<int>{1, 1},
                                         std::vector<int>{0, 1, 2, 3, 0, 1, 2}}) {
    options.information_quadratic_states = &states;
    GaussianXd s = prior;
    EXPECT_THROW(filter.update(s, model, y, r, options), s2kf::DimensionError);
    EXPECT_EQ(s.mean, prior.mean);
  }
}
