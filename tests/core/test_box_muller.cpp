#include <s2kf/core/box_muller.hpp>
#include <s2kf/core/constants.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using s2kf::box_muller;

TEST(BoxMuller, RadiusAndAngleComeFromTheTwoUniforms) {
  // ln u1 = -1/2 gives radius 1; u2 a quarter turn at a time.
  const double u1 = std::exp(-0.5);
  const auto [a0, b0] = box_muller(u1, 0.0);
  EXPECT_NEAR(a0, 1.0, 1e-15);
  EXPECT_NEAR(b0, 0.0, 1e-15);
  const auto [a1, b1] = box_muller(u1, 0.25);
  EXPECT_NEAR(a1, 0.0, 1e-15);
  EXPECT_NEAR(b1, 1.0, 1e-15);
  const auto [a2, b2] = box_muller(u1, 0.5);
  EXPECT_NEAR(a2, -1.0, 1e-15);
  EXPECT_NEAR(b2, 0.0, 1e-15);
  // u1 = 1: radius 0; u1 near 0: a large but finite radius.
  const auto [a3, b3] = box_muller(1.0, 0.3);
  EXPECT_EQ(a3, 0.0);
  EXPECT_EQ(b3, 0.0);
  const auto [a4, b4] = box_muller(1e-300, 0.0);
  EXPECT_NEAR(a4, std::sqrt(2 * 300 * std::log(10.0)), 1e-9);
  EXPECT_TRUE(std::isfinite(b4));
}

TEST(BoxMuller, PairsAreIndependentStandardNormals) {
  std::mt19937_64 rng(20261127);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const int pairs = 200000;
  double sum[2] = {0, 0}, square[2] = {0, 0}, fourth[2] = {0, 0}, product = 0;
  int inside = 0;
  for (int i = 0; i < pairs; ++i) {
    const auto [a, b] = box_muller(1.0 - uniform(rng), uniform(rng));
    const double z[2] = {a, b};
    for (int c = 0; c < 2; ++c) {
      sum[c] += z[c];
      square[c] += z[c] * z[c];
      fourth[c] += std::pow(z[c], 4);
      inside += std::abs(z[c]) < 1.959963984540054;
    }
    product += a * b;
  }
  // Tolerances of about six standard errors at 200,000 pairs.
  for (int c = 0; c < 2; ++c) {
    EXPECT_NEAR(sum[c] / pairs, 0.0, 0.014);
    EXPECT_NEAR(square[c] / pairs, 1.0, 0.02);
    EXPECT_NEAR(fourth[c] / pairs, 3.0, 0.13);  // a normal's kurtosis
  }
  EXPECT_NEAR(product / pairs, 0.0, 0.014);          // the two draws uncorrelated
  EXPECT_NEAR(inside / (2.0 * pairs), 0.95, 0.003);  // the 95 % interval
}

}  // namespace
