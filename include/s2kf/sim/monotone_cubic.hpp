/// @file
/// Monotone piecewise-cubic interpolation (Fritsch-Carlson / PCHIP): between two knots the curve
/// never leaves the interval spanned by their values, so keyframes inside the joint limits give a
/// trajectory inside the limits at every instant, and a plateau in the keyframes stays flat.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <utility>
#include <vector>

namespace s2kf::sim {

/// A C1 piecewise cubic Hermite curve through (times[i], values[i]). The knot slopes follow
/// Fritsch and Butland's weighted harmonic mean (as SciPy's PchipInterpolator): zero at a local
/// extremum of the data, otherwise at most three times the smaller adjacent secant, which is
/// Fritsch and Carlson's sufficient condition for monotonicity on every interval. Outside
/// [times.front(), times.back()] the curve holds the end value.
class MonotoneCubic {
 public:
  MonotoneCubic(std::vector<double> times, std::vector<double> values)
      : times_(std::move(times)), values_(std::move(values)) {
    if (times_.empty() || times_.size() != values_.size())
      throw std::invalid_argument("monotone cubic: need as many values as times, at least one");
    for (std::size_t i = 0; i < times_.size(); ++i) {
      if (!std::isfinite(times_[i]) || !std::isfinite(values_[i]))
        throw std::invalid_argument("monotone cubic: times and values must be finite");
      if (i > 0 && !(times_[i] > times_[i - 1]))
        throw std::invalid_argument("monotone cubic: times must be strictly increasing");
    }
    slopes_ = knot_slopes(times_, values_);
  }

  double operator()(double t) const {
    if (times_.size() == 1 || t <= times_.front()) return values_.front();
    if (t >= times_.back()) return values_.back();
    const std::size_t i = interval(t);
    const double h = times_[i + 1] - times_[i];
    const double s = (t - times_[i]) / h;
    const double s2 = s * s, s3 = s2 * s;
    // The Hermite form regrouped around values_[i], so a flat stretch evaluates exactly flat.
    return values_[i] + (3 * s2 - 2 * s3) * (values_[i + 1] - values_[i]) +
           (s3 - 2 * s2 + s) * h * slopes_[i] + (s3 - s2) * h * slopes_[i + 1];
  }

  /// The first derivative (0 outside the knot range).
  double derivative(double t) const {
    if (times_.size() == 1 || t < times_.front() || t > times_.back()) return 0.0;
    const std::size_t i = t >= times_.back() ? times_.size() - 2 : interval(t);
    const double h = times_[i + 1] - times_[i];
    const double s = (t - times_[i]) / h;
    const double s2 = s * s;
    return (6 * s2 - 6 * s) / h * values_[i] + (3 * s2 - 4 * s + 1) * slopes_[i] +
           (-6 * s2 + 6 * s) / h * values_[i + 1] + (3 * s2 - 2 * s) * slopes_[i + 1];
  }

  const std::vector<double>& slopes() const { return slopes_; }

 private:
  // Index i with times[i] <= t < times[i+1], for t inside the knot range.
  std::size_t interval(double t) const {
    const auto upper = std::upper_bound(times_.begin(), times_.end(), t);
    return static_cast<std::size_t>(upper - times_.begin()) - 1;
  }

  static std::vector<double> knot_slopes(const std::vector<double>& x, const std::vector<double>& y) {
    const std::size_t n = x.size();
    std::vector<double> d(n, 0.0);
    if (n < 2) return d;
    std::vector<double> h(n - 1), delta(n - 1);
    for (std::size_t k = 0; k + 1 < n; ++k) {
      h[k] = x[k + 1] - x[k];
      delta[k] = (y[k + 1] - y[k]) / h[k];
    }
    if (n == 2) {  // a straight line
      d[0] = d[1] = delta[0];
      return d;
    }
    for (std::size_t k = 1; k + 1 < n; ++k) {
      if (delta[k - 1] * delta[k] <= 0.0) continue;  // extremum or plateau: flat
      const double w1 = 2 * h[k] + h[k - 1];
      const double w2 = h[k] + 2 * h[k - 1];
      d[k] = (w1 + w2) / (w1 / delta[k - 1] + w2 / delta[k]);
    }
    d[0] = end_slope(h[0], h[1], delta[0], delta[1]);
    d[n - 1] = end_slope(h[n - 2], h[n - 3], delta[n - 2], delta[n - 3]);
    return d;
  }

  // Non-centred three-point end slope, limited so that the end interval stays monotone.
  static double end_slope(double h0, double h1, double delta0, double delta1) {
    double d = ((2 * h0 + h1) * delta0 - h0 * delta1) / (h0 + h1);
    if (d * delta0 <= 0.0) return 0.0;
    if (delta0 * delta1 < 0.0 && std::abs(d) > 3 * std::abs(delta0)) d = 3 * delta0;
    return d;
  }

  std::vector<double> times_, values_, slopes_;
};

}  // namespace s2kf::sim
