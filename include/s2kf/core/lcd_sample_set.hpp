/// @file
/// Optimal symmetric sample sets of the S2KF: L equally weighted samples {+s_k, -s_k} (+ origin)
/// minimising the LCD distance to N(0, I), found by L-BFGS from a seeded random start and then
/// moment-corrected to exact zero mean and identity covariance.
#pragma once

#include <s2kf/core/box_muller.hpp>
#include <s2kf/core/compilation_mode.hpp>

#include <s2kf/core/error.hpp>
#include <s2kf/core/lcd_distance.hpp>
#include <s2kf/core/sample_set.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf {

/// Settings of compute_lcd_sample_set. Every field changes the result, so all of them are part of
/// the key of the disk cache (sample_cache.hpp).
struct LcdOptions {
  double bmax = 0.0;                 ///< largest kernel width; 0 picks default_bmax(dimension)
  std::uint64_t seed = 1;            ///< seed of the random start (std::mt19937_64 + Box-Muller)
  int max_iterations = 2000;         ///< L-BFGS iterations at most
  double gradient_tolerance = 1e-8;  ///< stop when max |dD/ds| <= this
  /// Stop when an iteration lowers the distance D by at most this fraction of D. Measured against
  /// D (about 1e-2), not against the optimised -2 D2 + D3 (about -bmax^2/2), which would stop
  /// after a few iterations.
  double relative_tolerance = 1e-6;
  int history = 10;  ///< L-BFGS memory (pairs of steps and gradient changes)
};

/// A computed (or cached) sample set and how it was obtained.
struct LcdResult {
  SampleSet set;          ///< kind "lcd", N x L points, weights 1/L
  double distance = 0.0;  ///< lcd_distance of the final, moment-corrected set (D1 included)
  int iterations = 0;     ///< L-BFGS iterations of the computation
  double seconds = 0.0;   ///< wall time of the computation; 0 when loaded from the cache
  bool cached = false;    ///< true when loaded from the disk cache
};

// The optimiser behind compute_lcd_sample_set, compiled with it (compilation_mode.hpp).

/// Computes the optimal symmetric LCD sample set with `count` samples in `dimension` dimensions
/// (no cache: see lcd_sample_set in sample_cache.hpp). Needs count >= 2 * dimension. The same
/// arguments give the same set on the same platform. Throws DimensionError for impossible sizes and
/// std::invalid_argument for nonsensical options.
LcdResult compute_lcd_sample_set(int dimension, int count, const LcdOptions& options = {});

}  // namespace s2kf

#if !defined(S2KF_COMPILED)
#include <s2kf/core/lcd_sample_set.hxx>
#endif
