/// @file
/// The Box-Muller transform: two independent standard normal draws from two uniform ones. Written
/// out (std::normal_distribution is implementation-defined) so that a seed gives the same numbers
/// with every standard library; only the last bits of log/cos/sin may differ between C libraries.
#pragma once

#include <s2kf/core/constants.hpp>

#include <cmath>
#include <utility>

namespace s2kf {

/// (sqrt(-2 ln u1) cos(2 pi u2), sqrt(-2 ln u1) sin(2 pi u2)) for u1 in (0, 1] (so ln u1 is finite)
/// and u2 in [0, 1).
inline std::pair<double, double> box_muller(double u1, double u2) {
  const double radius = std::sqrt(-2.0 * std::log(u1));
  const double angle = 2 * kPi * u2;
  return {radius * std::cos(angle), radius * std::sin(angle)};
}

}  // namespace s2kf
