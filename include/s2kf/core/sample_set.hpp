/// @file
/// Deterministic and random sample sets approximating the standard normal N(0, I), and the
/// moment correction that makes their mean exactly 0 and covariance exactly I.
#pragma once

#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/error.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>

namespace s2kf {

/// Samples z_i (columns of points, dimension x count) with weights w_i for N(0, I).
/// Invariant after construction by the functions below: sum w_i z_i = 0 and
/// sum w_i z_i z_i^T = I to rounding, weights positive and summing to 1.
struct SampleSet {
  Eigen::MatrixXd points;
  Eigen::VectorXd weights;
  std::string kind;  ///< "lcd", "ukf", "random" or a user's name

  Eigen::Index dimension() const { return points.rows(); }
  Eigen::Index count() const { return points.cols(); }
};

/// Makes the equally weighted set z exactly zero-mean (subtracting the sample mean) and exactly
/// identity-covariance: C = Z Z^T / L, A = chol(C^-1) lower, Z <- A^T Z.
/// Throws DimensionError when the samples do not span the space (C singular).
void correct_moments(Eigen::MatrixXd& z);

/// The unscented set: the origin and +-sqrt(N + kappa) e_k. With kappa = 0.5 (the default) all
/// 2N + 1 weights are equal, 1 / (2N + 1), which is the "UKF-sized" set of the tracking comparison.
inline SampleSet ukf_sample_set(int dimension, double kappa = 0.5) {
  if (dimension < 1) throw DimensionError("ukf_sample_set: dimension must be at least 1");
  if (!(dimension + kappa > 0)) throw DimensionError("ukf_sample_set: N + kappa must be positive");
  const Eigen::Index n = dimension;
  SampleSet set;
  set.kind = "ukf";
  set.points = Eigen::MatrixXd::Zero(n, 2 * n + 1);
  set.weights.resize(2 * n + 1);
  const double spread = std::sqrt(n + kappa);
  set.weights(0) = kappa / (n + kappa);
  for (Eigen::Index k = 0; k < n; ++k) {
    set.points(k, 1 + k) = spread;
    set.points(k, 1 + n + k) = -spread;
    set.weights(1 + k) = set.weights(1 + n + k) = 0.5 / (n + kappa);
  }
  return set;
}

/// Equally weighted i.i.d. N(0, I) draws from a seeded generator, moment-corrected: a baseline to
/// compare optimal sets against. Needs count > dimension.
inline SampleSet random_sample_set(int dimension, int count, std::uint64_t seed) {
  if (dimension < 1 || count <= dimension)
    throw DimensionError("random_sample_set: need dimension >= 1 and count > dimension");
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  SampleSet set;
  set.kind = "random";
  set.points.resize(dimension, count);
  for (Eigen::Index j = 0; j < count; ++j)
    for (Eigen::Index i = 0; i < dimension; ++i) set.points(i, j) = normal(rng);
  correct_moments(set.points);
  set.weights = Eigen::VectorXd::Constant(count, 1.0 / count);
  return set;
}

/// Wraps user-supplied equally weighted samples (already moment-corrected by the caller or not).
inline SampleSet equally_weighted(Eigen::MatrixXd points, std::string kind) {
  SampleSet set;
  set.weights = Eigen::VectorXd::Constant(points.cols(), 1.0 / static_cast<double>(points.cols()));
  set.points = std::move(points);
  set.kind = std::move(kind);
  return set;
}

}  // namespace s2kf

#if !defined(S2KF_COMPILED)
#include <s2kf/core/sample_set.hxx>
#endif
