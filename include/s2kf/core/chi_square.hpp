/// @file
/// Chi-square distribution function and quantile, used to gate measurements by their NIS.
#pragma once

#include <cmath>
#include <limits>
#include <stdexcept>

namespace s2kf {

/// Regularised lower incomplete gamma function P(a, x) (series below a + 1, Lentz continued
/// fraction above, as in the standard numerical treatment; both converge to full double precision).
inline double regularized_gamma_p(double a, double x) {
  if (!(a > 0) || !(x >= 0)) throw std::invalid_argument("regularized_gamma_p: need a > 0 and x >= 0");
  if (x == 0) return 0.0;
  const double log_prefactor = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 10000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-17) break;
    }
    return std::exp(log_prefactor) * sum;
  }
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int n = 1; n < 10000; ++n) {
    const double an = -n * (n - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < 1e-16) break;
  }
  return 1.0 - std::exp(log_prefactor) * h;
}

/// P(X <= x) for X ~ chi-square with dof degrees of freedom.
inline double chi_square_cdf(double x, double dof) {
  return x <= 0 ? 0.0 : regularized_gamma_p(dof / 2, x / 2);
}

/// The x with chi_square_cdf(x, dof) = probability, by bisection on a bracket (robust, ~60 steps).
inline double chi_square_quantile(double probability, double dof) {
  if (!(probability > 0 && probability < 1) || !(dof > 0))
    throw std::invalid_argument("chi_square_quantile: need 0 < probability < 1 and dof > 0");
  double lo = 0, hi = dof + 10 * std::sqrt(2 * dof) + 10;
  while (chi_square_cdf(hi, dof) < probability) hi *= 2;
  for (int i = 0; i < 200 && hi - lo > 1e-14 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chi_square_cdf(mid, dof) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace s2kf
