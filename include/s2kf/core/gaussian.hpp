/// @file
/// Gaussian state estimate N(mean, covariance), fixed-size or dynamic-size.
#pragma once

#include <Eigen/Core>

namespace s2kf {

/// A Gaussian estimate. Invariant the filter keeps: covariance is symmetric positive definite.
/// Dim is a compile-time size or Eigen::Dynamic.
template <typename Scalar = double, int Dim = Eigen::Dynamic>
struct Gaussian {
  using Vector = Eigen::Matrix<Scalar, Dim, 1>;
  using Matrix = Eigen::Matrix<Scalar, Dim, Dim>;

  Vector mean;
  Matrix covariance;

  Gaussian() = default;
  Gaussian(Vector m, Matrix c) : mean(std::move(m)), covariance(std::move(c)) {}

  Eigen::Index dimension() const { return mean.size(); }
};

using GaussianXd = Gaussian<double, Eigen::Dynamic>;

}  // namespace s2kf
