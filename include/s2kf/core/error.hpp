/// @file
/// Failure reports of the estimation core: values the caller inspects, never asserts.
#pragma once

#include <stdexcept>
#include <string>

namespace s2kf {

/// Thrown for a programming error by the caller that no data could cause: dimensions that do not
/// fit together, an empty sample set. Numeric trouble (a covariance that is not positive definite,
/// a model returning NaN) is reported through FilterStatus instead.
struct DimensionError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// Outcome of a filter step. Every status other than ok leaves the estimate untouched.
enum class FilterStatus {
  ok,
  nothing_observed,                  ///< no measurement component observed: the update is a no-op
  prior_not_positive_definite,       ///< the covariance to sample from has no Cholesky factor
  innovation_not_positive_definite,  ///< Cyy (with R) has no Cholesky factor
  posterior_not_positive_definite,   ///< C - A A^T lost definiteness (too little noise for the data)
  non_finite_model_output,           ///< the model returned NaN or infinity for some sample
  non_finite_measurement,            ///< an observed measurement component is NaN or infinite
  gated,                             ///< NIS above the gate: the measurement was rejected as an outlier
};

inline const char* to_string(FilterStatus status) {
  switch (status) {
    case FilterStatus::ok:
      return "ok";
    case FilterStatus::nothing_observed:
      return "nothing observed";
    case FilterStatus::prior_not_positive_definite:
      return "prior covariance not positive definite";
    case FilterStatus::innovation_not_positive_definite:
      return "innovation covariance not positive definite";
    case FilterStatus::posterior_not_positive_definite:
      return "posterior covariance not positive definite";
    case FilterStatus::non_finite_model_output:
      return "model output not finite";
    case FilterStatus::non_finite_measurement:
      return "measurement not finite";
    case FilterStatus::gated:
      return "measurement rejected by the gate";
  }
  return "unknown";
}

}  // namespace s2kf
