#include <s2kf/core/chi_square.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace {

using s2kf::chi_square_cdf;
using s2kf::chi_square_quantile;

// Closed forms of the chi-square distribution function for 1, 2, 4 and 6 degrees of freedom.
double closed_form_cdf(double x, int dof) {
  const double h = x / 2;
  switch (dof) {
    case 1:
      return std::erf(std::sqrt(h));
    case 2:
      return 1 - std::exp(-h);
    case 4:
      return 1 - std::exp(-h) * (1 + h);
    default:  // 6
      return 1 - std::exp(-h) * (1 + h + h * h / 2);
  }
}

TEST(ChiSquare, DistributionFunctionMatchesTheClosedForms) {
  // x from far below to far above the mean: the series (x < dof/2 + 1) and the continued fraction.
  for (int dof : {1, 2, 4, 6})
    for (double x : {1e-6, 0.01, 0.5, 1.0, 2.9, 3.0, 3.1, 7.9, 8.0, 8.1, 20.0, 60.0})
      EXPECT_NEAR(chi_square_cdf(x, dof), closed_form_cdf(x, dof), 1e-14) << "dof " << dof << " x " << x;
  EXPECT_EQ(chi_square_cdf(0.0, 3), 0.0);
  EXPECT_EQ(chi_square_cdf(-1.0, 3), 0.0);
}

TEST(ChiSquare, QuantileInvertsTheDistributionFunction) {
  for (double dof : {1.0, 2.0, 3.0, 6.0, 12.0, 100.0})
    for (double p : {1e-4, 0.01, 0.5, 0.95, 0.999, 1 - 1e-9}) {
      const double x = chi_square_quantile(p, dof);
      EXPECT_NEAR(chi_square_cdf(x, dof), p, 1e-12) << "dof " << dof << " p " << p;
    }
  // Two degrees of freedom: x = -2 ln(1 - p).
  for (double p : {0.1, 0.9, 0.99}) EXPECT_NEAR(chi_square_quantile(p, 2), -2 * std::log1p(-p), 1e-12);
  // The tables' 95 % point for three degrees of freedom (a 3D marker's gate).
  EXPECT_NEAR(chi_square_quantile(0.95, 3), 7.814727903251178, 1e-9);
}

TEST(ChiSquare, RefusesArgumentsOutsideTheDomain) {
  EXPECT_THROW(chi_square_quantile(0.0, 3), std::invalid_argument);
  EXPECT_THROW(chi_square_quantile(1.0, 3), std::invalid_argument);
  EXPECT_THROW(chi_square_quantile(0.5, 0), std::invalid_argument);
  EXPECT_THROW(chi_square_quantile(std::nan(""), 3), std::invalid_argument);
  EXPECT_THROW(s2kf::regularized_gamma_p(-1, 1), std::invalid_argument);
  EXPECT_THROW(s2kf::regularized_gamma_p(1, -1), std::invalid_argument);
}

}  // namespace
