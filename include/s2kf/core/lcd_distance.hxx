/// @file
/// The definitions of <s2kf/core/lcd_distance.hpp>: inline where the library is used header-only, compiled
/// once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/core/lcd_distance.hpp>

namespace s2kf {

S2KF_INLINE void detail::gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights) {
  nodes.assign(static_cast<std::size_t>(n), 0.0);
  weights.assign(static_cast<std::size_t>(n), 0.0);
  const double pi = kPi;
  // P_n(x) (p0) and P_{n-1}(x) (p1) by the three-term recurrence.
  const auto legendre = [n](double x, double& p0, double& p1) {
    p0 = 1.0;
    p1 = 0.0;
    for (int j = 1; j <= n; ++j) {
      const double p2 = p1;
      p1 = p0;
      p0 = ((2.0 * j - 1.0) * x * p1 - (j - 1.0) * p2) / j;
    }
  };
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double x = std::cos(pi * (i + 0.75) / (n + 0.5));
    double derivative = 0.0, p0 = 0.0, p1 = 0.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      legendre(x, p0, p1);
      derivative = n * (x * p0 - p1) / (x * x - 1.0);
      const double step = p0 / derivative;
      x -= step;
      if (std::abs(step) <= 1e-16) break;
    }
    // One more derivative at the converged node for the weight.
    legendre(x, p0, p1);
    derivative = n * (x * p0 - p1) / (x * x - 1.0);
    const double weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
    nodes[static_cast<std::size_t>(i)] = -x;
    nodes[static_cast<std::size_t>(n - 1 - i)] = x;
    weights[static_cast<std::size_t>(i)] = weights[static_cast<std::size_t>(n - 1 - i)] = weight;
  }
}

S2KF_INLINE void detail::lcd_b_rule(double bmax, int per_interval, std::vector<double>& nodes,
                                    std::vector<double>& weights) {
  std::vector<double> x, w;
  gauss_legendre(per_interval, x, w);
  nodes.clear();
  weights.clear();
  double left = 0.0;
  double right = std::min(0.5, bmax);
  while (left < bmax) {
    const double half = 0.5 * (right - left), mid = 0.5 * (right + left);
    for (std::size_t i = 0; i < x.size(); ++i) {
      nodes.push_back(mid + half * x[i]);
      weights.push_back(half * w[i]);
    }
    left = right;
    right = std::min(2.0 * right, bmax);
    // Do not leave a sliver: merge a last interval shorter than a quarter of its predecessor.
    if (right < bmax && bmax - right < 0.25 * (right - left)) right = bmax;
  }
}

S2KF_INLINE double lcd_distance(const Eigen::MatrixXd& samples, double bmax) {
  if (samples.rows() < 1 || samples.cols() < 1) throw DimensionError("lcd_distance: the sample set is empty");
  LcdObjective objective(static_cast<int>(samples.rows()), bmax);
  return objective.distance(samples);
}

S2KF_INLINE double LcdObjective::evaluate(const Eigen::Ref<const Eigen::MatrixXd>& samples,
                                          Eigen::Ref<Eigen::MatrixXd> gradient) {
  check_rows(samples.rows(), "evaluate");
  const Eigen::Index count = samples.cols();
  if (count < 1) throw DimensionError("LcdObjective::evaluate: the sample set is empty");
  if (gradient.rows() != samples.rows() || gradient.cols() != count)
    throw DimensionError("LcdObjective::evaluate: the gradient must have the shape of the samples");
  const double w = 1.0 / static_cast<double>(count);
  gram_.resize(count, count);
  gram_.noalias() = samples.transpose() * samples;
  radius_ = gram_.diagonal();
  coefficient_.resize(count);
  row_sum_.setZero(count);
  // Pairwise part: D3 = w^2 (L g(0) + 2 sum_{i<j} g(d_ij)); gradient 4 w^2 sum_j g'(d_ij)(x_i - x_j).
  double pair_sum = 0.0;
  for (Eigen::Index j = 0; j < count; ++j) {
    gram_(j, j) = 0.0;
    for (Eigen::Index i = 0; i < j; ++i) {
      const double d = std::max(0.0, radius_(i) + radius_(j) - 2.0 * gram_(i, j));
      double g, dg;
      pair_kernel(d, g, dg);
      pair_sum += g;
      gram_(i, j) = gram_(j, i) = dg;  // the Gram matrix is no longer needed: reuse it for g'
      row_sum_(i) += dg;
      row_sum_(j) += dg;
    }
  }
  double value = w * w * (static_cast<double>(count) * 0.125 * scale_ + 2.0 * pair_sum);
  double radial_sum = 0.0;
  for (Eigen::Index i = 0; i < count; ++i) {
    double h, hq;
    radial_integrals(radius_(i), h, hq);
    radial_sum += h;
    coefficient_(i) = 4.0 * w * hq + 4.0 * w * w * row_sum_(i);
  }
  value -= 2.0 * w * radial_sum;
  gradient.noalias() = samples * coefficient_.asDiagonal();
  gradient.noalias() -= (4.0 * w * w) * (samples * gram_);
  return value;
}

}  // namespace s2kf
