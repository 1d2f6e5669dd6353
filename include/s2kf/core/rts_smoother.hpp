/// @file
/// Rauch-Tung-Striebel smoothing for the random-walk prediction x_{k+1} = x_k + w_k, w_k ~ N(0, Q),
/// the prediction the S2KF tracker uses. Offline: the backward pass runs over the filter's stored
/// posteriors once the recording has been filtered.
#pragma once

#include <s2kf/core/error.hpp>
#include <s2kf/core/gaussian.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <string>
#include <vector>

namespace s2kf {

/// The identity chart change: for filters whose state coordinates never change between steps.
struct SameChart {
  void operator()(std::size_t /*step*/, Eigen::VectorXd& /*mean*/, Eigen::MatrixXd& /*covariance*/) const {}
};

/// Smoothed Gaussians from the filtered ones. filtered[k] is the posterior at step k; the
/// prediction of step k+1 is N(m_k, P_k + Q). With G_k = P_k (P_k + Q)^-1:
///   m^s_k = m_k + G_k (m^s_{k+1} - m_k),   P^s_k = P_k + G_k (P^s_{k+1} - P_k - Q) G_k^T.
/// Filters that re-centre their state after an update (the tracker folds its orientation error
/// into a reference rotation) express step k+1 in other coordinates than step k:
/// `to_chart_of(k, mean, covariance)` rewrites a Gaussian given in the coordinates of step k+1 in
/// those of step k, in place. A step whose P + Q has no Cholesky factor keeps its filtered value.
template <typename ChartChange = SameChart>
std::vector<GaussianXd> rts_smooth_random_walk(const std::vector<GaussianXd>& filtered,
                                               const Eigen::MatrixXd& q, ChartChange&& to_chart_of = {}) {
  std::vector<GaussianXd> smoothed(filtered.size());
  if (filtered.empty()) return smoothed;
  const Eigen::Index n = filtered.back().dimension();
  if (q.rows() != n || q.cols() != n)
    throw DimensionError("rts_smooth_random_walk: Q is " + std::to_string(q.rows()) + "x" +
                         std::to_string(q.cols()) + ", expected " + std::to_string(n) + "x" +
                         std::to_string(n));
  smoothed.back() = filtered.back();
  Eigen::LLT<Eigen::MatrixXd> predicted_factor(n);
  Eigen::MatrixXd predicted(n, n), gain(n, n);
  for (std::size_t k = filtered.size() - 1; k-- > 0;) {
    const GaussianXd& f = filtered[k];
    if (f.dimension() != n || f.covariance.rows() != n || f.covariance.cols() != n)
      throw DimensionError("rts_smooth_random_walk: step " + std::to_string(k) + " has another dimension");
    predicted = f.covariance + q;
    predicted_factor.compute(predicted);
    if (predicted_factor.info() != Eigen::Success) {  // numeric trouble: keep the filtered step
      smoothed[k] = f;
      continue;
    }
    // G = P (P + Q)^-1, and both are symmetric: G^T = (P + Q)^-1 P.
    gain.noalias() = predicted_factor.solve(f.covariance).transpose();
    Eigen::VectorXd next_mean = smoothed[k + 1].mean;
    Eigen::MatrixXd next_covariance = smoothed[k + 1].covariance;
    to_chart_of(k, next_mean, next_covariance);
    GaussianXd& s = smoothed[k];
    s.mean = f.mean + gain * (next_mean - f.mean);
    s.covariance = f.covariance + gain * (next_covariance - predicted) * gain.transpose();
    s.covariance = 0.5 * (s.covariance + s.covariance.transpose()).eval();
  }
  return smoothed;
}

}  // namespace s2kf
