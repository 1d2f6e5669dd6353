/// @file
/// Rauch-Tung-Striebel smoothing for a linear prediction x_{k+1} = A x_k + w_k, w_k ~ N(0, Q): the
/// S2KF tracker's random walk (A = I) and its constant-velocity model. Offline: the backward pass runs over
/// the filter's stored posteriors once the recording has been filtered.
#pragma once

#include <s2kf/core/error.hpp>
#include <s2kf/core/gaussian.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <string>
#include <utility>
#include <vector>

namespace s2kf {

/// The identity chart change: for filters whose state coordinates never change between steps.
struct SameChart {
  void operator()(std::size_t /*step*/, Eigen::VectorXd& /*mean*/, Eigen::MatrixXd& /*covariance*/) const {}
};

/// Smoothed Gaussians from the filtered ones for the linear prediction x_{k+1} = A x_k + w_k,
/// w_k ~ N(0, Q). filtered[k] is the posterior at step k; the prediction of step k+1 is
/// N(A m_k, A P_k A^T + Q) =: N(m^-, P^-). With G_k = P_k A^T (P^-)^-1:
///   m^s_k = m_k + G_k (m^s_{k+1} - m^-),   P^s_k = P_k + G_k (P^s_{k+1} - P^-) G_k^T.
/// Filters that re-centre their state after an update (the tracker folds its orientation error
/// into a reference rotation) express step k+1 in other coordinates than step k:
/// `to_chart_of(k, mean, covariance)` rewrites a Gaussian given in the coordinates of step k+1 in
/// those of step k, in place. A step whose P^- has no Cholesky factor keeps its filtered value.
template <typename ChartChange = SameChart>
std::vector<GaussianXd> rts_smooth_linear(const std::vector<GaussianXd>& filtered, const Eigen::MatrixXd& a,
                                          const Eigen::MatrixXd& q, ChartChange&& to_chart_of = {}) {
  std::vector<GaussianXd> smoothed(filtered.size());
  if (filtered.empty()) return smoothed;
  const Eigen::Index n = filtered.back().dimension();
  const auto check = [n](const Eigen::MatrixXd& m, const char* name) {
    if (m.rows() != n || m.cols() != n)
      throw DimensionError(std::string("rts_smooth_linear: ") + name + " is " + std::to_string(m.rows()) +
                           "x" + std::to_string(m.cols()) + ", expected " + std::to_string(n) + "x" +
                           std::to_string(n));
  };
  check(q, "Q");
  check(a, "A");
  const bool identity = a.isIdentity(0);  // the random walk: no products with A
  smoothed.back() = filtered.back();
  Eigen::LLT<Eigen::MatrixXd> predicted_factor(n);
  Eigen::MatrixXd predicted(n, n), gain(n, n), cross(n, n);
  Eigen::VectorXd predicted_mean(n);
  for (std::size_t k = filtered.size() - 1; k-- > 0;) {
    const GaussianXd& f = filtered[k];
    if (f.dimension() != n || f.covariance.rows() != n || f.covariance.cols() != n)
      throw DimensionError("rts_smooth_linear: step " + std::to_string(k) + " has another dimension");
    if (identity) {
      cross = f.covariance;  // P A^T
      predicted_mean = f.mean;
    } else {
      cross.noalias() = f.covariance * a.transpose();
      predicted_mean.noalias() = a * f.mean;
    }
    predicted = q;
    if (identity)
      predicted += f.covariance;
    else
      predicted.noalias() += a * cross;
    predicted_factor.compute(predicted);
    if (predicted_factor.info() != Eigen::Success) {  // numeric trouble: keep the filtered step
      smoothed[k] = f;
      continue;
    }
    // G = P A^T (P^-)^-1, and P^- is symmetric: G^T = (P^-)^-1 (P A^T)^T.
    gain.noalias() = predicted_factor.solve(cross.transpose()).transpose();
    Eigen::VectorXd next_mean = smoothed[k + 1].mean;
    Eigen::MatrixXd next_covariance = smoothed[k + 1].covariance;
    to_chart_of(k, next_mean, next_covariance);
    GaussianXd& s = smoothed[k];
    s.mean = f.mean + gain * (next_mean - predicted_mean);
    s.covariance = f.covariance + gain * (next_covariance - predicted) * gain.transpose();
    s.covariance = 0.5 * (s.covariance + s.covariance.transpose()).eval();
  }
  return smoothed;
}

/// The random walk x_{k+1} = x_k + w_k (A = I), the prediction of the paper's S2KF tracker:
/// G_k = P_k (P_k + Q)^-1, m^s_k = m_k + G_k (m^s_{k+1} - m_k), P^s_k = P_k + G_k (P^s_{k+1} - P_k - Q)
/// G_k^T.
template <typename ChartChange = SameChart>
std::vector<GaussianXd> rts_smooth_random_walk(const std::vector<GaussianXd>& filtered,
                                               const Eigen::MatrixXd& q, ChartChange&& to_chart_of = {}) {
  if (filtered.empty()) return {};
  const Eigen::Index n = filtered.back().dimension();
  if (q.rows() != n || q.cols() != n)
    throw DimensionError("rts_smooth_random_walk: Q is " + std::to_string(q.rows()) + "x" +
                         std::to_string(q.cols()) + ", expected " + std::to_string(n) + "x" +
                         std::to_string(n));
  return rts_smooth_linear(filtered, Eigen::MatrixXd::Identity(n, n), q,
                           std::forward<ChartChange>(to_chart_of));
}

}  // namespace s2kf
