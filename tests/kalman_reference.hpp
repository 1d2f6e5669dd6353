/// @file
/// The closed-form Kalman update and random test matrices that the filter's tests compare against.
#pragma once

#include <s2kf/core/gaussian.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>

#include <Eigen/Core>
#include <Eigen/LU>

#include <algorithm>
#include <random>
#include <vector>

namespace s2kf::test {

inline Eigen::MatrixXd random_matrix(int rows, int cols, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd a(rows, cols);
  for (int i = 0; i < a.size(); ++i) a.data()[i] = normal(rng);
  return a;
}

inline Eigen::MatrixXd random_spd(int n, std::mt19937_64& rng) {
  const Eigen::MatrixXd a = random_matrix(n, n, rng);
  return a * a.transpose() + 0.5 * Eigen::MatrixXd::Identity(n, n);
}

/// The closed-form Kalman update on the observed rows only, written out with an explicit inverse.
inline void kalman_update(GaussianXd& s, const Eigen::MatrixXd& h, const Eigen::VectorXd& y,
                          const Eigen::MatrixXd& r, const ObservedMask& observed) {
  std::vector<int> rows;
  for (int i = 0; i < observed.size(); ++i)
    if (observed(i)) rows.push_back(i);
  const int mo = static_cast<int>(rows.size());
  Eigen::MatrixXd ho(mo, h.cols()), ro(mo, mo);
  Eigen::VectorXd yo(mo);
  for (int i = 0; i < mo; ++i) {
    ho.row(i) = h.row(rows[i]);
    yo(i) = y(rows[i]);
    for (int j = 0; j < mo; ++j) ro(i, j) = r(rows[i], rows[j]);
  }
  const Eigen::MatrixXd sm = ho * s.covariance * ho.transpose() + ro;
  const Eigen::MatrixXd k = s.covariance * ho.transpose() * sm.inverse();
  s.mean = s.mean + k * (yo - ho * s.mean);
  s.covariance = s.covariance - k * ho * s.covariance;
}

inline double relative_error(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max(1.0, b.norm());
}

/// y = H x + offset for every sample.
struct LinearModel {
  Eigen::MatrixXd h;
  Eigen::VectorXd offset;
  void operator()(const Eigen::MatrixXd& x, Eigen::MatrixXd& y) const {
    y = h * x;
    y.colwise() += offset;
  }
};

}  // namespace s2kf::test
