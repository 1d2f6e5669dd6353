/// @file
/// Carrying an update of some components of a Gaussian to the others. When a measurement depends
/// on the first n components p of a state [p, v] only, the filter may update the marginal of p
/// alone (with its n-dimensional samples) and bring v along afterwards: v is independent of the
/// measurement given p, so p(v | y) = integral of p(v | p) p(p | y) dp, which for a Gaussian prior
/// is exactly
///   K = C_vp C_pp^-1,   v+ = v + K (p+ - p),   C_vp+ = K C_pp+,   C_vv+ = C_vv - K (C_pp - C_pp+) K^T.
/// This is the linear-Gaussian conditioning a full Kalman update of [p, v] with a measurement
/// matrix [H 0] performs, at the cost of a few n x n products.
#pragma once

#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/error.hpp>
#include <s2kf/core/gaussian.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <string>

namespace s2kf {

/// Keeps its scratch between calls, so a filter that runs it every step does not allocate.
class MarginalUpdate {
 public:
  /// `joint` is the prior over [p, v] (p: its first head_posterior.dimension() components);
  /// `head_posterior` the updated Gaussian of p. Writes the posterior of [p, v] into `joint`.
  /// Returns false, and leaves `joint` as it was, when the prior C_pp has no Cholesky factor.
  bool apply(GaussianXd& joint, const GaussianXd& head_posterior);

 private:
  Eigen::LLT<Eigen::MatrixXd> factor_;
  Eigen::MatrixXd gain_, shrink_, product_;
};

// Defined once in the compiled library, or inline (core/compilation_mode.hpp).

}  // namespace s2kf

#if !defined(S2KF_COMPILED)
#include <s2kf/core/marginal_update.hxx>
#endif
