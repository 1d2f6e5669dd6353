// UpdateOptions::block_dependencies: states that no observed block reads take their update only
// through their prior regression on the states that are read, in both gains; without the lists a
// finite sample set's spurious cross-covariance moves them.
#include <s2kf/core/lcd_sample_set.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>

#include "kalman_reference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace {

using s2kf::GaussianXd;
using s2kf::ObservedMask;
using s2kf::S2kf;
using s2kf::UpdateOptions;
using s2kf::test::random_matrix;
using s2kf::test::random_spd;

constexpr int kStates = 5;

// Three blocks of three components. Blocks 0 and 1 read states 0 and 1 only, block 2 reads
// states 0 and 4: with block 2 hidden, states 2, 3 and 4 are read by nothing observed.
struct ChainModel {
  void operator()(const Eigen::MatrixXd& x, Eigen::MatrixXd& y) const {
    for (Eigen::Index i = 0; i < x.cols(); ++i) {
      const double a = x(0, i), b = x(1, i), e = x(4, i);
      y.col(i) << std::sin(2 * a) + b, a * b, std::cos(a) + 0.5 * b,  //
          a + 0.3 * b * b, std::sin(a + b), b,                        //
          a + std::sin(e), e * e, std::cos(e);
    }
  }
};

const std::vector<std::vector<int>> kDependencies = {{0, 1}, {0, 1}, {0, 4}};

UpdateOptions options(bool information_form, const std::vector<std::vector<int>>* dependencies) {
  UpdateOptions o;
  o.block_size = 3;
  o.information_form = information_form;
  o.block_dependencies = dependencies;
  return o;
}

ObservedMask first_two_blocks() {
  ObservedMask observed = ObservedMask::Constant(9, true);
  observed.tail(3).setConstant(false);
  return observed;
}

GaussianXd correlated_prior(std::mt19937_64& rng) {
  return GaussianXd(random_matrix(kStates, 1, rng) * 0.3, random_spd(kStates, rng) * 0.2);
}

TEST(BlockDependencies, UnreadStatesFollowTheirPriorRegressionOnTheReadStates) {
  // o = {0, 1} read, u = {2, 3, 4} not: the update of a model that reads only x_o moves x_u by
  // P_uo P_oo^-1 times the step of x_o, and takes P_uu down by P_uo P_oo^-1 (P_oo - P+_oo)
  // P_oo^-1 P_ou (the Gaussian conditioning closed form), in either gain.
  std::mt19937_64 rng(71);
  const Eigen::VectorXd y = random_matrix(9, 1, rng);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(9, 9) * 0.05;
  for (const bool information_form : {false, true}) {
    const GaussianXd prior = correlated_prior(rng);
    GaussianXd posterior = prior;
    S2kf filter(s2kf::compute_lcd_sample_set(kStates, 61).set);
    ASSERT_TRUE(filter
                    .update(posterior, ChainModel{}, y, r, first_two_blocks(),
                            options(information_form, &kDependencies))
                    .ok());
    const Eigen::MatrixXd p_oo = prior.covariance.topLeftCorner(2, 2);
    const Eigen::MatrixXd p_uo = prior.covariance.bottomLeftCorner(3, 2);
    const Eigen::MatrixXd regression = p_uo * p_oo.inverse();
    const Eigen::VectorXd step_o = posterior.mean.head(2) - prior.mean.head(2);
    ASSERT_GT(step_o.norm(), 1e-3) << "the read states must move for the check to mean anything";
    const Eigen::VectorXd expected_u = prior.mean.tail(3) + regression * step_o;
    EXPECT_LT((posterior.mean.tail(3) - expected_u).norm(), 1e-10) << information_form;
    const Eigen::MatrixXd shrink = p_oo - posterior.covariance.topLeftCorner(2, 2);
    const Eigen::MatrixXd expected_uu =
        prior.covariance.bottomRightCorner(3, 3) - regression * shrink * regression.transpose();
    EXPECT_LT((posterior.covariance.bottomRightCorner(3, 3) - expected_uu).norm(), 1e-10) << information_form;
    const Eigen::MatrixXd expected_uo = p_uo - regression * shrink;
    EXPECT_LT((posterior.covariance.bottomLeftCorner(3, 2) - expected_uo).norm(), 1e-10) << information_form;
  }
}

TEST(BlockDependencies, WithoutTheListsTheSampleSetsNoiseMovesUncorrelatedUnreadStates) {
  // A prior in which x_u is uncorrelated with x_o: with the lists x_u keeps its mean and
  // covariance exactly; without them the sample cross-covariance of a finite set (its third
  // and higher moments are not those of a Gaussian) moves it, which is what the lists remove.
  std::mt19937_64 rng(72);
  const Eigen::VectorXd y = random_matrix(9, 1, rng);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(9, 9) * 0.05;
  GaussianXd prior = correlated_prior(rng);
  prior.covariance.bottomLeftCorner(3, 2).setZero();
  prior.covariance.topRightCorner(2, 3).setZero();
  for (const bool information_form : {false, true}) {
    GaussianXd with = prior, without = prior;
    S2kf filter(s2kf::compute_lcd_sample_set(kStates, 61).set);
    ASSERT_TRUE(
        filter.update(with, ChainModel{}, y, r, first_two_blocks(), options(information_form, &kDependencies))
            .ok());
    ASSERT_TRUE(
        filter.update(without, ChainModel{}, y, r, first_two_blocks(), options(information_form, nullptr))
            .ok());
    EXPECT_LT((with.mean.tail(3) - prior.mean.tail(3)).norm(), 1e-12) << information_form;
    EXPECT_LT((with.covariance.bottomRightCorner(3, 3) - prior.covariance.bottomRightCorner(3, 3)).norm(),
              1e-12)
        << information_form;
    EXPECT_LT(with.covariance.bottomLeftCorner(3, 2).norm(), 1e-12) << information_form;
    EXPECT_GT((without.mean.tail(3) - prior.mean.tail(3)).norm(), 1e-5) << information_form;
    // The ordinary gain's read states are those of the update without the lists: only Cyx's
    // unread columns change.
    if (!information_form) {
      EXPECT_LT((with.mean.head(2) - without.mean.head(2)).norm(), 1e-12);
    }
  }
}

TEST(BlockDependencies, WhenEveryStateIsReadTheUpdateIsUnchanged) {
  // Block 2 observed: every state but 2 and 3 is read; lists that name all five states for
  // every block leave nothing unread, and the update is the plain one to the last bit.
  std::mt19937_64 rng(73);
  const Eigen::VectorXd y = random_matrix(9, 1, rng);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(9, 9) * 0.05;
  const std::vector<std::vector<int>> all(3, std::vector<int>{0, 1, 2, 3, 4});
  for (const bool information_form : {false, true}) {
    const GaussianXd prior = correlated_prior(rng);
    GaussianXd with = prior, without = prior;
    S2kf filter(s2kf::compute_lcd_sample_set(kStates, 61).set);
    ASSERT_TRUE(filter.update(with, ChainModel{}, y, r, options(information_form, &all)).ok());
    ASSERT_TRUE(filter.update(without, ChainModel{}, y, r, options(information_form, nullptr)).ok());
    EXPECT_EQ(with.mean, without.mean) << information_form;
    EXPECT_EQ(with.covariance, without.covariance) << information_form;
  }
}

TEST(BlockDependencies, ListsThatDoNotFitAreRefused) {
  std::mt19937_64 rng(74);
  const Eigen::VectorXd y = random_matrix(9, 1, rng);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(9, 9) * 0.05;
  GaussianXd state = correlated_prior(rng);
  S2kf filter(s2kf::compute_lcd_sample_set(kStates, 61).set);
  const std::vector<std::vector<int>> too_few = {{0, 1}, {0, 1}};
  const std::vector<std::vector<int>> out_of_range = {{0, 1}, {0, 5}, {0, 4}};
  EXPECT_THROW(filter.update(state, ChainModel{}, y, r, options(true, &too_few)), s2kf::DimensionError);
  EXPECT_THROW(filter.update(state, ChainModel{}, y, r, options(false, &out_of_range)), s2kf::DimensionError);
}

}  // namespace
