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

/// Frames in one second at `rate_hz` (at least one): the window converged_frame looks ahead over.
inline long frames_per_second(double rate_hz) {
  return std::isfinite(rate_hz) && rate_hz >= 1 ? std::lround(rate_hz) : 1L;
}

/// converged_frame's search with the threshold given (factor times a median known otherwise), over
/// the first `starts` frames (-1: all of them).
inline long converged_frame_below(const std::vector<double>& distance, long window, double threshold,
                                  long starts = -1) {
  if (!std::isfinite(threshold)) return -1;
  const std::size_t width = static_cast<std::size_t>(std::max(1L, window));
  const std::size_t end =
      starts < 0 ? distance.size() : std::min(distance.size(), static_cast<std::size_t>(starts));
  std::vector<double> ahead;
  for (std::size_t f = 0; f < end; ++f) {
    if (!std::isfinite(distance[f])) continue;
    ahead.clear();
    for (std::size_t k = f; k < std::min(distance.size(), f + width); ++k)
      if (std::isfinite(distance[k])) ahead.push_back(distance[k]);
    if (quantile(ahead, 0.5) < threshold) return static_cast<long>(f);
  }
  return -1;
}

/// The first frame at which the filter has converged: the first measured frame from which the
/// running median of the distance over the next `window` frames (one second, frames_per_second;
/// fewer at the end) falls below `factor` times the median over the whole recording. NaN frames
/// (untracked, without markers) are left out of both medians. A late fast phase does not move it:
/// the rule looks forward from the start, it does not restart. -1 when no frame qualifies.
inline long converged_frame(const std::vector<double>& distance, long window, double factor = 1.5) {
  return converged_frame_below(distance, window, factor * quantile(distance, 0.5));
}

/// Mean of the finite values from `from` on.
inline double mean_from(const std::vector<double>& values, long from) {
  double sum = 0;
  long count = 0;
  for (std::size_t f = static_cast<std::size_t>(std::max(0L, from)); f < values.size(); ++f)
    if (std::isfinite(values[f])) sum += values[f], ++count;
  return count ? sum / static_cast<double>(count) : std::numeric_limits<double>::quiet_NaN();
}

/// The mean distance from converged_frame(distance, window) on: the level after convergence; NaN
/// when the distance never converged.
inline double level_after_convergence(const std::vector<double>& distance, long window) {
  const long converged = converged_frame(distance, window);
  return converged >= 0 ? mean_from(distance, converged) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace s2kf::track
