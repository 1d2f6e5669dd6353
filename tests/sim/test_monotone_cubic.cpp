// The monotone cubic (PCHIP) interpolation that turns keyframes into trajectories.
#include <s2kf/sim/monotone_cubic.hpp>
#include <s2kf/sim/random.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

namespace {

using s2kf::sim::MonotoneCubic;

TEST(MonotoneCubic, PassesThroughEveryKnot) {
  const MonotoneCubic curve({0.0, 0.5, 1.5, 2.0, 4.0}, {1.0, -2.0, 3.0, 3.0, 0.5});
  EXPECT_DOUBLE_EQ(curve(0.0), 1.0);
  EXPECT_DOUBLE_EQ(curve(0.5), -2.0);
  EXPECT_DOUBLE_EQ(curve(1.5), 3.0);
  EXPECT_DOUBLE_EQ(curve(2.0), 3.0);
  EXPECT_DOUBLE_EQ(curve(4.0), 0.5);
}

// Hand-derived from the Fritsch-Butland formulas: x = (0, 1, 3), y = (0, 2, 3) gives secants
// (2, 0.5), interior slope 9 / (5/2 + 4/0.5) = 6/7, end slopes 2.5 and 0 (the three-point end
// formula gives -0.5, against the secant's sign, so it is set to 0). At x = 0.5 the Hermite basis
// is (1/2, 1/8, 1/2, -1/8): 0.3125 + 1 - 3/28.
TEST(MonotoneCubic, MatchesHandDerivedSlopesAndValue) {
  const MonotoneCubic curve({0.0, 1.0, 3.0}, {0.0, 2.0, 3.0});
  ASSERT_EQ(curve.slopes().size(), 3u);
  EXPECT_NEAR(curve.slopes()[0], 2.5, 1e-15);
  EXPECT_NEAR(curve.slopes()[1], 6.0 / 7.0, 1e-15);
  EXPECT_NEAR(curve.slopes()[2], 0.0, 1e-15);
  EXPECT_NEAR(curve(0.5), 0.3125 + 1.0 - 3.0 / 28.0, 1e-14);
}

TEST(MonotoneCubic, ReproducesAStraightLine) {
  const MonotoneCubic curve({0.0, 0.3, 1.0, 2.5}, {1.0, 1.6, 3.0, 6.0});
  for (double t = 0.0; t <= 2.5; t += 0.01) {
    EXPECT_NEAR(curve(t), 1.0 + 2.0 * t, 1e-12);
    EXPECT_NEAR(curve.derivative(t), 2.0, 1e-12);
  }
}

TEST(MonotoneCubic, HoldsTheEndValuesOutsideTheKnots) {
  const MonotoneCubic curve({1.0, 2.0, 3.0}, {5.0, 7.0, 4.0});
  EXPECT_EQ(curve(-10.0), 5.0);
  EXPECT_EQ(curve(0.999), 5.0);
  EXPECT_EQ(curve(3.5), 4.0);
  EXPECT_EQ(curve.derivative(10.0), 0.0);
  const MonotoneCubic single({2.0}, {3.0});
  EXPECT_EQ(single(0.0), 3.0);
  EXPECT_EQ(single(5.0), 3.0);
}

// Brute force over many random data sets: between two knots the curve never leaves the interval
// of their values (no overshoot), and it is monotone there.
TEST(MonotoneCubic, NeverOvershootsTheKnotsOnRandomData) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 9);
    std::vector<double> x(n), y(n);
    double t = s2kf::sim::uniform(rng, -1, 1);
    for (int i = 0; i < n; ++i) {
      t += s2kf::sim::uniform(rng, 0.01, 2.0);
      x[i] = t;
      // Plateaus and sharp steps are where naive splines overshoot most.
      y[i] = (i > 0 && rng() % 4 == 0) ? y[i - 1] : s2kf::sim::uniform(rng, -3, 3);
    }
    const MonotoneCubic curve(x, y);
    for (int i = 0; i + 1 < n; ++i) {
      const double lo = std::min(y[i], y[i + 1]), hi = std::max(y[i], y[i + 1]);
      const double tolerance = 1e-12 * (1.0 + std::abs(lo) + std::abs(hi));
      double previous = curve(x[i]);
      for (int s = 1; s <= 200; ++s) {
        const double value = curve(x[i] + (x[i + 1] - x[i]) * s / 200.0);
        ASSERT_GE(value, lo - tolerance) << "trial " << trial << " interval " << i;
        ASSERT_LE(value, hi + tolerance) << "trial " << trial << " interval " << i;
        if (y[i + 1] >= y[i])
          ASSERT_GE(value, previous - tolerance);
        else
          ASSERT_LE(value, previous + tolerance);
        previous = value;
      }
    }
  }
}

TEST(MonotoneCubic, IsContinuouslyDifferentiableAndItsDerivativeIsRight) {
  const std::vector<double> x{0.0, 0.4, 1.0, 1.7, 2.0, 3.1};
  const MonotoneCubic curve(x, {0.0, 1.0, 0.2, 0.9, 1.4, -0.3});
  const double h = 1e-6;
  for (double t = 0.01; t < 3.09; t += 0.037) {
    const double finite_difference = (curve(t + h) - curve(t - h)) / (2 * h);
    EXPECT_NEAR(curve.derivative(t), finite_difference, 1e-6) << "t = " << t;
  }
  for (std::size_t i = 1; i + 1 < x.size(); ++i) {  // same slope from both sides of each knot
    const double left = (curve(x[i]) - curve(x[i] - h)) / h;
    const double right = (curve(x[i] + h) - curve(x[i])) / h;
    EXPECT_NEAR(left, right, 1e-4) << "knot " << i;
    EXPECT_NEAR(curve.derivative(x[i]), curve.slopes()[i], 1e-12);
  }
}

TEST(MonotoneCubic, RejectsBadKnots) {
  EXPECT_THROW(MonotoneCubic({}, {}), std::invalid_argument);
  EXPECT_THROW(MonotoneCubic({0.0, 1.0}, {1.0}), std::invalid_argument);
  EXPECT_THROW(MonotoneCubic({0.0, 0.0}, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(MonotoneCubic({1.0, 0.0}, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(MonotoneCubic({0.0, 1.0}, {1.0, std::nan("")}), std::invalid_argument);
}

}  // namespace
