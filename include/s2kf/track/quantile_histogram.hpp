/// @file
/// Count, sum, mean, min, max and quantiles of a stream of non-negative values (times, distances)
/// in fixed memory: what a run of unbounded length (s2kf live) reports per frame without keeping
/// every frame's value.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace s2kf::track {

/// Values go into log-spaced bins whose representative is within `resolution` (relative) of every
/// value in the bin (DDSketch's bins: Masson, Rim, Lee, VLDB 2019), so a quantile is within
/// `resolution` of the exact one (track::quantile: linear interpolation between the order statistics
/// around q (n - 1)) for values in [lowest, highest]. Values below `lowest` (zero, and negative ones)
/// share one bin reported as the smallest value seen, values above `highest` one reported as the
/// largest; every reported quantile lies in [min, max], q = 0 is min and q = 1 max, exactly. Values
/// that are not finite (NaN, infinities) are skipped. The default 0.5 % over [1e-9, 1e9] takes 4,147
/// bins (33 kB), whatever the number of values.
class QuantileHistogram {
 public:
  explicit QuantileHistogram(double resolution = 0.005, double lowest = 1e-9, double highest = 1e9)
      : resolution_(resolution),
        lowest_(lowest),
        log_gamma_(std::log((1 + resolution) / (1 - resolution))),
        counts_(static_cast<std::size_t>(std::ceil(std::log(highest / lowest) / log_gamma_)) + 2, 0) {}

  /// Adds a value; NaN and infinities are skipped.
  void add(double value) {
    if (!std::isfinite(value)) return;
    ++counts_[bin(value)];
    ++count_;
    sum_ += value;
    min_ = std::min(min_, value);
    max_ = std::max(max_, value);
  }

  double resolution() const { return resolution_; }
  std::size_t bin_count() const { return counts_.size(); }
  std::int64_t count() const { return count_; }
  /// The values added in order (as a loop over them would add them).
  double sum() const { return sum_; }
  double mean() const { return count_ ? sum_ / static_cast<double>(count_) : nan(); }
  double min() const { return count_ ? min_ : nan(); }
  double max() const { return count_ ? max_ : nan(); }

  /// The q-quantile (q in 0..1, clamped), interpolated as track::quantile; NaN without values.
  double quantile(double q) const {
    if (count_ == 0 || std::isnan(q)) return nan();
    const double position = std::clamp(q, 0.0, 1.0) * static_cast<double>(count_ - 1);
    const auto below = static_cast<std::int64_t>(std::floor(position));
    const std::int64_t above = std::min(below + 1, count_ - 1);
    const double low = order_statistic(below), high = order_statistic(above);
    return low + (position - static_cast<double>(below)) * (high - low);
  }

 private:
  static double nan() { return std::numeric_limits<double>::quiet_NaN(); }

  /// 0: below lowest; k + 1: [lowest gamma^k, lowest gamma^(k+1)); the last: above highest.
  std::size_t bin(double value) const {
    if (value < lowest_) return 0;
    const double k = std::floor(std::log(value / lowest_) / log_gamma_);
    return static_cast<std::size_t>(std::min(k + 1, static_cast<double>(counts_.size() - 1)));
  }

  /// The value of the rank-th smallest (0-based): its bin's representative, within [min, max].
  double order_statistic(std::int64_t rank) const {
    if (rank == 0) return min_;
    if (rank == count_ - 1) return max_;
    std::int64_t seen = 0;
    std::size_t b = 0;
    while (seen + counts_[b] <= rank) seen += counts_[b++];
    if (b == 0) return min_;
    if (b == counts_.size() - 1) return max_;
    // 2 gamma / (1 + gamma) times the bin's lower edge: relative error at most `resolution` at both
    // edges.
    const double lower_edge = lowest_ * std::exp(static_cast<double>(b - 1) * log_gamma_);
    const double representative = lower_edge * 2 / (1 + std::exp(-log_gamma_));
    return std::clamp(representative, min_, max_);
  }

  double resolution_, lowest_, log_gamma_;
  std::vector<std::int64_t> counts_;
  std::int64_t count_ = 0;
  double sum_ = 0;
  double min_ = std::numeric_limits<double>::infinity();
  double max_ = -std::numeric_limits<double>::infinity();
};

}  // namespace s2kf::track
