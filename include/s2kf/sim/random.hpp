/// @file
/// Reproducible random draws for the simulator: the same seed gives the same numbers with every
/// standard library, because the distributions are written here on top of std::mt19937_64 (whose
/// output the standard fixes) instead of the implementation-defined std:: distributions.
#pragma once

#include <s2kf/core/box_muller.hpp>

#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>

namespace s2kf::sim {

/// A seed for an independent stream `stream` of the generator seeded with `seed` (SplitMix64
/// finaliser), so that switching one perturbation off never changes the draws of another.
inline std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/// Uniform in [0, 1) with 53 random bits.
inline double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

/// Uniform in [a, b).
inline double uniform(std::mt19937_64& rng, double a, double b) { return a + (b - a) * uniform01(rng); }

/// Standard normal draw (Box-Muller; one of the pair is discarded to keep the generator stateless).
inline double standard_normal(std::mt19937_64& rng) {
  const double u1 = 1.0 - uniform01(rng);  // in (0, 1]: log stays finite
  const double u2 = uniform01(rng);
  return box_muller(u1, u2).first;
}

/// The largest Poisson mean `poisson` accepts: the exact method below costs O(lambda) draws.
inline constexpr double kMaxPoissonMean = 1.0e5;

/// Poisson(lambda) draw, exact: Knuth's product method on pieces of mean <= 30 (a sum of
/// independent Poisson variables is Poisson with the summed mean), so exp(-piece) never underflows.
inline long poisson(std::mt19937_64& rng, double lambda) {
  if (!(lambda >= 0.0) || lambda > kMaxPoissonMean)
    throw std::invalid_argument("the Poisson mean must lie in [0, 1e5]");
  long count = 0;
  double remaining = lambda;
  while (remaining > 0.0) {
    const double piece = remaining > 30.0 ? 30.0 : remaining;
    remaining -= piece;
    const double limit = std::exp(-piece);
    double product = uniform01(rng);
    while (product >= limit) {
      ++count;
      product *= uniform01(rng);
    }
  }
  return count;
}

}  // namespace s2kf::sim
