/// @file
/// Summary numbers of a tracked recording (docs/results.md): frames to converge, the distance
/// level after convergence, latency percentiles.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace s2kf::track {

/// The q-quantile (0..1) of the finite values, linear interpolation; NaN when there are none.
inline double quantile(std::vector<double> values, double q) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
               values.end());
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double position = q * static_cast<double>(values.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const auto above = std::min(below + 1, values.size() - 1);
  return values[below] + (position - static_cast<double>(below)) * (values[above] - values[below]);
}

/// The final level of a per-frame distance series: the median over its second half (finite values).
inline double final_level(const std::vector<double>& distance) {
  std::vector<double> tail(distance.begin() + static_cast<std::ptrdiff_t>(distance.size() / 2),
                           distance.end());
  return quantile(tail, 0.5);
}

/// First frame after which the distance stays within `factor` times its final level (NaN frames,
/// untracked or without markers, do not break the run). -1 when the series has no finite value.
inline long converged_frame(const std::vector<double>& distance, double factor = 1.5) {
  const double level = final_level(distance);
  if (!std::isfinite(level)) return -1;
  long first = 0;
  for (std::size_t f = 0; f < distance.size(); ++f) {
    if (!std::isfinite(distance[f])) {
      if (static_cast<long>(f) == first) ++first;  // leading untracked frames
      continue;
    }
    if (distance[f] > factor * level) first = static_cast<long>(f) + 1;
  }
  return first;
}

/// Mean of the finite values from `from` on.
inline double mean_from(const std::vector<double>& values, long from) {
  double sum = 0;
  long count = 0;
  for (std::size_t f = static_cast<std::size_t>(std::max(0L, from)); f < values.size(); ++f)
    if (std::isfinite(values[f])) sum += values[f], ++count;
  return count ? sum / static_cast<double>(count) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace s2kf::track
