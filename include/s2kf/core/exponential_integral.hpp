/// @file
/// The exponential integral E1(x) = int_x^inf exp(-t)/t dt for x > 0 and Ei(x) = -E1(-x) for x < 0,
/// the special function in the pairwise terms of the LCD distance.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace s2kf {

namespace detail {

inline constexpr double euler_gamma = 0.57721566490153286060651209008240243;

/// Coefficients of the convergent series E1(x) = -gamma - ln x - sum_{k>=1} (-x)^k / (k k!), stored
/// as a_k = (-1)^(k+1) / (k k!) so that E1(x) = -gamma - ln x + x (a_1 + x (a_2 + ...)).
template <std::size_t Terms>
constexpr std::array<double, Terms> e1_series_coefficients() {
  std::array<double, Terms> a{};
  double factorial = 1.0;
  for (std::size_t k = 1; k <= Terms; ++k) {
    factorial *= static_cast<double>(k);
    const double sign = (k % 2 == 1) ? 1.0 : -1.0;
    a[k - 1] = sign / (static_cast<double>(k) * factorial);
  }
  return a;
}

/// sum_{k=1}^{Terms} a_k x^k by Horner's rule.
template <std::size_t Terms>
inline double e1_series_sum(double x) {
  static constexpr std::array<double, Terms> a = e1_series_coefficients<Terms>();
  double sum = a[Terms - 1];
  for (std::size_t k = Terms - 1; k-- > 0;) sum = a[k] + x * sum;
  return x * sum;
}

/// The part of E1 that is not -ln x, for 0 < x <= 1: -gamma + sum a_k x^k. The number of terms is
/// chosen so that the first omitted term is below 1e-17 relative to E1(x): 10 terms for x <= 1/8
/// (0.125^11 / (11 * 11!) ~ 2e-19), 19 terms for x <= 1 (1 / (20 * 20!) ~ 2e-20).
inline double e1_series_remainder(double x) {
  return -euler_gamma + (x <= 0.125 ? e1_series_sum<10>(x) : e1_series_sum<19>(x));
}

/// E1(x) for x > 1 by the continued fraction E1(x) = exp(-x) / (x + 1 - 1^2/(x + 3 - 2^2/(x + 5 - ...))),
/// evaluated with the modified Lentz algorithm. Converges in under 30 steps at x = 1, fewer above.
inline double e1_continued_fraction(double x) {
  constexpr double tiny = 1e-300;
  constexpr double eps = std::numeric_limits<double>::epsilon();
  double b = x + 1.0;
  double c = 1.0 / tiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i < 200; ++i) {
    const double an = -static_cast<double>(i) * static_cast<double>(i);
    b += 2.0;
    d = 1.0 / (an * d + b);
    c = b + an / c;
    const double delta = c * d;
    h *= delta;
    if (std::abs(delta - 1.0) <= eps) break;
  }
  return h * std::exp(-x);
}

}  // namespace detail

/// E1(x) = int_x^inf exp(-t)/t dt for x > 0 (relative error about 1e-15). E1(0) = +inf; a negative
/// or NaN argument gives NaN (E1 is complex there).
inline double exponential_integral_e1(double x) {
  if (!(x >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
  if (x == 0.0) return std::numeric_limits<double>::infinity();
  if (x <= 1.0) return detail::e1_series_remainder(x) - std::log(x);
  if (x > 745.0) return 0.0;  // below the smallest subnormal
  return detail::e1_continued_fraction(x);
}

/// Ei(x) for x <= 0, i.e. -E1(-x): the exponential integral as it appears in the LCD distance.
/// Ei(0) = -inf; a positive or NaN argument gives NaN (only the negative axis is needed here).
inline double exponential_integral_ei(double x) {
  if (!(x <= 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return -exponential_integral_e1(-x);
}

}  // namespace s2kf
