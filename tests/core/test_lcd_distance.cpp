// The exponential integral, the LCD distance against a brute-force evaluation of its defining
// integral, and the analytic gradients against central differences.
#include <s2kf/core/exponential_integral.hpp>
#include <s2kf/core/lcd_distance.hpp>
#include <s2kf/core/lcd_sample_set.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace {

using s2kf::LcdObjective;

// Composite Gauss-Legendre on [a, b] with `pieces` equal subintervals of `nodes` nodes: the
// reference rule of these tests, deliberately unlike the library's doubling intervals.
double integrate(const std::function<double(double)>& f, double a, double b, int pieces, int nodes = 20) {
  std::vector<double> x, w;
  s2kf::detail::gauss_legendre(nodes, x, w);
  double sum = 0.0;
  const double width = (b - a) / pieces;
  for (int p = 0; p < pieces; ++p) {
    const double mid = a + (p + 0.5) * width, half = 0.5 * width;
    for (std::size_t i = 0; i < x.size(); ++i) sum += half * w[i] * f(mid + half * x[i]);
  }
  return sum;
}

Eigen::MatrixXd random_points(int rows, int cols, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd points(rows, cols);
  for (Eigen::Index i = 0; i < points.size(); ++i) points.data()[i] = normal(rng);
  return points;
}

TEST(ExponentialIntegral, MatchesTabulatedValues) {
  // Tabulated E1 (Abramowitz & Stegun 5.1; values to 16 digits).
  EXPECT_NEAR(s2kf::exponential_integral_e1(1.0), 0.21938393439552026, 1e-14 * 0.22);
  EXPECT_NEAR(s2kf::exponential_integral_e1(0.5), 0.5597735947761608, 1e-14 * 0.56);
  EXPECT_NEAR(s2kf::exponential_integral_e1(2.0), 0.04890051070806112, 1e-14 * 0.049);
  EXPECT_NEAR(s2kf::exponential_integral_e1(10.0), 4.156968929685324e-06, 1e-14 * 4.2e-6);
  // Ei(x) = -E1(-x) on the negative axis.
  EXPECT_NEAR(s2kf::exponential_integral_ei(-1.0), -0.21938393439552026, 1e-14 * 0.22);
}

TEST(ExponentialIntegral, MatchesHighPrecisionValuesAcrossBranches) {
  // 20-digit values (computed with mpmath.e1) on both sides of the series / continued-fraction switch.
  const std::vector<std::pair<double, double>> table = {
      {1e-6, 13.238295893062491289},    {0.01, 4.0379295765381138112},     {0.1, 1.8229239584193906159},
      {0.7, 0.37376884323350917577},    {1.5, 0.1000195824066326519},      {3.0, 0.013048381094197037413},
      {7.5, 6.5830893267080230617e-05}, {25.0, 5.3488997553402166403e-13}, {80.0, 2.2285432586884729112e-37}};
  for (const auto& [x, e1] : table)
    EXPECT_NEAR(s2kf::exponential_integral_e1(x), e1, 2e-15 * e1) << "x = " << x;
}

TEST(ExponentialIntegral, MatchesNumericalIntegralOfExpOverT) {
  // E1(x) = int_x^inf exp(-t)/t dt = int_0^inf exp(-x - u)/(x + u) du, truncated where exp(-u) < 1e-30.
  for (double x : {0.05, 0.3, 0.99, 1.01, 4.0, 12.0}) {
    const double reference = integrate([x](double u) { return std::exp(-x - u) / (x + u); }, 0.0, 2.0, 400) +
                             integrate([x](double u) { return std::exp(-x - u) / (x + u); }, 2.0, 72.0, 140);
    EXPECT_NEAR(s2kf::exponential_integral_e1(x), reference, 1e-13 * reference) << "x = " << x;
  }
}

TEST(ExponentialIntegral, DomainEdges) {
  EXPECT_TRUE(std::isinf(s2kf::exponential_integral_e1(0.0)));
  EXPECT_TRUE(std::isnan(s2kf::exponential_integral_e1(-1.0)));
  EXPECT_TRUE(std::isnan(s2kf::exponential_integral_ei(0.5)));
  EXPECT_EQ(s2kf::exponential_integral_e1(800.0), 0.0);
  EXPECT_TRUE(std::isinf(s2kf::exponential_integral_ei(0.0)));
}

TEST(LcdDistance, DefaultBmaxTableAndSampleCount) {
  EXPECT_EQ(s2kf::default_bmax(1), 5.0);
  EXPECT_EQ(s2kf::default_bmax(2), 10.0);
  EXPECT_EQ(s2kf::default_bmax(10), 10.0);
  EXPECT_EQ(s2kf::default_bmax(11), 50.0);
  EXPECT_EQ(s2kf::default_bmax(46), 50.0);
  EXPECT_EQ(s2kf::default_bmax(100), 50.0);
  EXPECT_EQ(s2kf::default_bmax(101), 100.0);
  EXPECT_EQ(s2kf::default_bmax(1000), 100.0);
  EXPECT_EQ(s2kf::default_bmax(1001), 200.0);
  EXPECT_EQ(s2kf::default_sample_count(46), 461);
  EXPECT_EQ(s2kf::default_sample_count(1), 11);
  EXPECT_EQ(s2kf::default_sample_count(3), 31);
  EXPECT_THROW(s2kf::default_bmax(0), s2kf::DimensionError);
  EXPECT_THROW(s2kf::default_sample_count(-2), s2kf::DimensionError);
}

TEST(LcdDistance, ConstantTermMatchesClosedFormInTwoDimensions) {
  for (double bmax : {10.0, 3.7, 50.0}) {
    const LcdObjective objective(2, bmax);
    const double closed = 0.5 * (bmax * bmax - std::log1p(bmax * bmax));
    EXPECT_NEAR(objective.d1(), closed, 1e-13 * closed) << "bmax = " << bmax;
  }
}

TEST(LcdDistance, ConstantTermMatchesDirectQuadratureInOtherDimensions) {
  for (int n : {1, 3, 46}) {
    const double bmax = s2kf::default_bmax(n);
    const double reference =
        integrate([n](double b) { return std::pow(b * b / (1.0 + b * b), 0.5 * n) * b; }, 0.0, bmax, 2000);
    EXPECT_NEAR(LcdObjective(n, bmax).d1(), reference, 1e-12 * reference) << "N = " << n;
  }
}

// Brute force in 1-D: D = int_0^bmax w(b) int (F~(m, b) - F(m, b))^2 dm db, w(b) = 1/sqrt(pi), with
// the inner integral by the trapezoidal rule (spectrally accurate for these Gaussians when the step
// is b/2) over a range wide enough for the widest kernel.
double brute_force_distance_1d(const Eigen::MatrixXd& x, double bmax) {
  const double w = 1.0 / static_cast<double>(x.cols());
  const double reach = x.cwiseAbs().maxCoeff();
  auto inner = [&](double b) {
    const double width = std::sqrt(1.0 + b * b);
    const double range = reach + 12.0 * width;
    const double h = 0.5 * std::min(b, 1.0);
    const auto steps = static_cast<long>(std::ceil(2.0 * range / h));
    const double step = 2.0 * range / static_cast<double>(steps);
    const double normal_factor = std::sqrt(b * b / (1.0 + b * b));
    double sum = 0.0;
    for (long k = 0; k <= steps; ++k) {
      const double m = -range + step * static_cast<double>(k);
      double dirac = 0.0;
      for (Eigen::Index i = 0; i < x.cols(); ++i)
        dirac += w * std::exp(-(x(0, i) - m) * (x(0, i) - m) / (2 * b * b));
      const double normal = normal_factor * std::exp(-m * m / (2.0 * (1.0 + b * b)));
      sum += (normal - dirac) * (normal - dirac);
    }
    return step * sum;
  };
  const double pi = 3.14159265358979323846;
  // Finer pieces near 0 where the kernels are narrow.
  return (integrate(inner, 0.0, 0.5, 20) + integrate(inner, 0.5, bmax, 20)) / std::sqrt(pi);
}

TEST(LcdDistance, MatchesBruteForceIntegralInOneDimension) {
  Eigen::MatrixXd x(1, 3);
  x << -1.3, 0.2, 0.9;
  for (double bmax : {5.0, 2.0}) {
    const double reference = brute_force_distance_1d(x, bmax);
    EXPECT_NEAR(s2kf::lcd_distance(x, bmax), reference, 1e-10) << "bmax = " << bmax;
    EXPECT_GT(reference, 1e-3);  // the comparison is not between two zeros
  }
}

// Brute force in 2-D: the square (F~ - F)^2 expands into products of Gaussians that separate over
// the two coordinates, so each inner 2-D integral is a product of 1-D trapezoidal integrals; no
// closed-form Gaussian integral (and no Ei) enters.
double brute_force_distance_2d(const Eigen::MatrixXd& x, double bmax) {
  const double w = 1.0 / static_cast<double>(x.cols());
  const double reach = x.cwiseAbs().maxCoeff();
  const Eigen::Index count = x.cols();
  auto inner = [&](double b) {
    const double width = std::sqrt(1.0 + b * b);
    const double range = reach + 12.0 * width;
    const double h = 0.5 * std::min(b, 1.0);
    const auto steps = static_cast<long>(std::ceil(2.0 * range / h));
    const double step = 2.0 * range / static_cast<double>(steps);
    // Per coordinate d: integrals of normal^2, normal*kernel_i, kernel_i*kernel_j (1-D factors).
    Eigen::Vector2d nn = Eigen::Vector2d::Zero();
    Eigen::MatrixXd nk = Eigen::MatrixXd::Zero(2, count);
    std::vector<Eigen::MatrixXd> kk(2, Eigen::MatrixXd::Zero(count, count));
    Eigen::VectorXd kernel(count);
    for (int d = 0; d < 2; ++d) {
      for (long s = 0; s <= steps; ++s) {
        const double m = -range + step * static_cast<double>(s);
        const double normal = std::sqrt(b * b / (1.0 + b * b)) * std::exp(-m * m / (2.0 * (1.0 + b * b)));
        for (Eigen::Index i = 0; i < count; ++i)
          kernel(i) = std::exp(-(x(d, i) - m) * (x(d, i) - m) / (2 * b * b));
        nn(d) += step * normal * normal;
        nk.row(d) += step * normal * kernel.transpose();
        kk[static_cast<std::size_t>(d)] += step * kernel * kernel.transpose();
      }
    }
    double value = nn(0) * nn(1);
    for (Eigen::Index i = 0; i < count; ++i) {
      value -= 2.0 * w * nk(0, i) * nk(1, i);
      for (Eigen::Index j = 0; j < count; ++j) value += w * w * kk[0](i, j) * kk[1](i, j);
    }
    return value;
  };
  const double pi = 3.14159265358979323846;
  // w(b) = 1 / (pi b) in 2-D.
  auto weighted = [&](double b) { return inner(b) / (pi * b); };
  return integrate(weighted, 0.0, 0.5, 20) + integrate(weighted, 0.5, 2.0, 10) +
         integrate(weighted, 2.0, bmax, 20);
}

TEST(LcdDistance, MatchesBruteForceIntegralInTwoDimensions) {
  const Eigen::MatrixXd x = random_points(2, 4, 11);
  for (double bmax : {10.0, 3.0}) {
    const double reference = brute_force_distance_2d(x, bmax);
    EXPECT_NEAR(s2kf::lcd_distance(x, bmax), reference, 1e-9) << "bmax = " << bmax;
    EXPECT_GT(reference, 1e-3);
  }
}

TEST(LcdDistance, SymmetricFormEqualsGeneralFormOfTheExpandedSet) {
  for (int n : {1, 3, 7}) {
    const Eigen::MatrixXd half = random_points(n, 6, 20 + static_cast<std::uint64_t>(n));
    LcdObjective objective(n, s2kf::default_bmax(n));
    for (bool origin : {false, true}) {
      const Eigen::MatrixXd full = s2kf::detail::symmetric_set(half, origin);
      Eigen::MatrixXd g_full(full.rows(), full.cols()), g_half(half.rows(), half.cols());
      const double general = objective.evaluate(full, g_full);
      const double symmetric = objective.evaluate_symmetric(half, origin, g_half);
      EXPECT_NEAR(general, symmetric, 1e-12 * std::abs(general)) << "N = " << n << " origin = " << origin;
      // Each half sample appears as +s and -s: its gradient is twice that of +s in the full set.
      const Eigen::Index offset = origin ? 1 : 0;
      EXPECT_LT((g_half - 2.0 * g_full.middleCols(offset, half.cols())).cwiseAbs().maxCoeff(), 1e-12);
    }
  }
}

// Max |analytic - central difference| over all coordinates, relative to max |analytic|. The
// five-point stencil with h = 1e-3 keeps both the truncation error (h^4) and the rounding error of
// the large objective (about bmax^2/2 with D near 1e-2, so ~1e-13 / h) near 1e-10.
double gradient_error(const std::function<double(const Eigen::MatrixXd&, Eigen::MatrixXd&)>& f,
                      const Eigen::MatrixXd& x) {
  Eigen::MatrixXd gradient(x.rows(), x.cols()), scratch(x.rows(), x.cols());
  f(x, gradient);
  double worst = 0.0;
  const double h = 1e-3;
  auto shifted = [&](Eigen::Index i, double by) {
    Eigen::MatrixXd moved = x;
    moved.data()[i] += by;
    return f(moved, scratch);
  };
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double numeric =
        (-shifted(i, 2 * h) + 8 * shifted(i, h) - 8 * shifted(i, -h) + shifted(i, -2 * h)) / (12.0 * h);
    worst = std::max(worst, std::abs(numeric - gradient.data()[i]));
  }
  return worst / gradient.cwiseAbs().maxCoeff();
}

TEST(LcdDistance, GeneralGradientMatchesCentralDifferences) {
  for (int n : {1, 2, 5}) {
    LcdObjective objective(n, s2kf::default_bmax(n));
    const Eigen::MatrixXd x = random_points(n, 7, 30 + static_cast<std::uint64_t>(n));
    const double error = gradient_error(
        [&](const Eigen::MatrixXd& p, Eigen::MatrixXd& g) { return objective.evaluate(p, g); }, x);
    EXPECT_LT(error, 1e-7) << "N = " << n;
  }
}

TEST(LcdDistance, SymmetricGradientMatchesCentralDifferences) {
  for (int n : {1, 3, 12}) {
    LcdObjective objective(n, s2kf::default_bmax(n));
    const Eigen::MatrixXd half = random_points(n, 5, 40 + static_cast<std::uint64_t>(n));
    for (bool origin : {false, true}) {
      const double error =
          gradient_error([&](const Eigen::MatrixXd& p,
                             Eigen::MatrixXd& g) { return objective.evaluate_symmetric(p, origin, g); },
                         half);
      EXPECT_LT(error, 1e-7) << "N = " << n << " origin = " << origin;
    }
  }
}

TEST(LcdDistance, CoincidentSamplesHaveAFiniteValueAndGradient) {
  Eigen::MatrixXd x(2, 3);
  x << 0.5, 0.5, -1.0, 0.2, 0.2, 0.0;
  LcdObjective objective(2, 10.0);
  Eigen::MatrixXd gradient(2, 3);
  EXPECT_TRUE(std::isfinite(objective.evaluate(x, gradient)));
  EXPECT_TRUE(gradient.allFinite());
  Eigen::MatrixXd half = Eigen::MatrixXd::Zero(2, 2);  // s_2 = 0 = -s_2 and s_1 = s_2
  Eigen::MatrixXd half_gradient(2, 2);
  EXPECT_TRUE(std::isfinite(objective.evaluate_symmetric(half, true, half_gradient)));
  EXPECT_TRUE(half_gradient.allFinite());
}

TEST(LcdDistance, RejectsMismatchedShapesAndBadBmax) {
  LcdObjective objective(3, 10.0);
  Eigen::MatrixXd x = random_points(2, 4, 1), g(2, 4);
  EXPECT_THROW(objective.evaluate(x, g), s2kf::DimensionError);
  EXPECT_THROW(LcdObjective(3, -1.0), s2kf::DimensionError);
  EXPECT_THROW(LcdObjective(0, 10.0), s2kf::DimensionError);
  EXPECT_THROW(s2kf::lcd_distance(Eigen::MatrixXd(0, 0), 5.0), s2kf::DimensionError);
}

TEST(LcdDistance, IsInvariantUnderRotation) {
  const Eigen::MatrixXd x = random_points(3, 9, 5);
  const double angle = 0.7;
  Eigen::Matrix3d rotation;
  rotation << std::cos(angle), -std::sin(angle), 0, std::sin(angle), std::cos(angle), 0, 0, 0, 1;
  EXPECT_NEAR(s2kf::lcd_distance(x, 10.0), s2kf::lcd_distance(rotation * x, 10.0), 1e-11);
}

}  // namespace
