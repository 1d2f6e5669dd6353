/// @file
/// Sine and cosine of a whole array at once, in loops the compiler vectorises (std::sin and
/// std::cos are scalar library calls and would dominate batched forward kinematics). Always
/// inlined, so that code compiled for another instruction set (core/instruction_set.hpp) vectorises
/// them with its own registers.
#pragma once

#include <s2kf/core/instruction_set.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <cstring>

namespace s2kf::body {

/// s[i] = sin(x[i]), c[i] = cos(x[i]) for i < n, within a few units in the last place of std::sin
/// and std::cos. Arguments with |x| <= 1e5 take the vectorised path (fdlibm's polynomials after a
/// three-part Cody-Waite reduction by pi/2, exact for these magnitudes); larger or non-finite
/// arguments fall back to std::sin/std::cos, so NaN and infinity give NaN exactly as there.
S2KF_ALWAYS_INLINE void vector_sincos(const double* x, double* s, double* c, Eigen::Index n) {
  constexpr double kTwoOverPi = 6.36619772367581382433e-01;
  constexpr double kPio2Part1 = 1.57079632673412561417e+00;  // first 33 bits of pi/2
  constexpr double kPio2Part2 = 6.07710050630396597660e-11;  // next 33 bits
  constexpr double kPio2Part3 = 2.02226624871116645580e-21;  // the rest
  constexpr double kRoundMagic = 6755399441055744.0;         // 1.5 * 2^52: adding it rounds to an integer
  constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                   S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                   S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                   C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                   C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  constexpr double kLimit = 1e5;  // k * kPio2Part1 stays exact while |k| < 2^20
  // Count of arguments for the scalar fallback (NaN included): an integer, whose sum the compiler
  // may reorder into vector lanes (a floating-point sum it must add in order, lane by lane).
  std::int64_t large = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double xi = x[i];
    const double shifted = xi * kTwoOverPi + kRoundMagic;  // its last two bits are k mod 4
    const double k = shifted - kRoundMagic;
    const double r = ((xi - k * kPio2Part1) - k * kPio2Part2) - k * kPio2Part3;  // |r| <= pi/4
    const double z = r * r;
    const double sin_r = r + z * r * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    const double hz = 0.5 * z;
    const double w = 1.0 - hz;
    const double cos_r =
        w + (((1.0 - w) - hz) + z * z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6))))));
    // Quadrant k mod 4 from the bits, with integer masks only (no branches or blends, so the loop
    // vectorises with SSE2 too): bit 0 swaps sine and cosine, bit 1 negates both.
    std::uint64_t quadrant, sin_bits, cos_bits;
    std::memcpy(&quadrant, &shifted, sizeof quadrant);
    std::memcpy(&sin_bits, &sin_r, sizeof sin_bits);
    std::memcpy(&cos_bits, &cos_r, sizeof cos_bits);
    constexpr std::uint64_t kSignBit = std::uint64_t(1) << 63;
    const std::uint64_t odd = std::uint64_t(0) - (quadrant & 1), flip = (quadrant & 2) << 62;
    const std::uint64_t sine = ((cos_bits & odd) | (sin_bits & ~odd)) ^ flip;
    const std::uint64_t cosine = (((sin_bits ^ kSignBit) & odd) | (cos_bits & ~odd)) ^ flip;
    std::memcpy(s + i, &sine, sizeof sine);
    std::memcpy(c + i, &cosine, sizeof cosine);
    large += std::abs(xi) <= kLimit ? 0 : 1;
  }
  if (large == 0) return;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (std::abs(x[i]) <= kLimit) continue;
    s[i] = std::sin(x[i]);
    c[i] = std::cos(x[i]);
  }
}

/// The single-precision version (the tracker's single-precision sample pipeline): Cephes' sinf and
/// cosf polynomials after a three-part reduction by pi/2 (exact for |x| <= 8192), within about two
/// units in the last place of float; larger or non-finite arguments take std::sin/std::cos.
S2KF_ALWAYS_INLINE void vector_sincos(const float* x, float* s, float* c, Eigen::Index n) {
  constexpr float kTwoOverPi = 0.636619772367581f;
  constexpr float kPio2Part1 = 1.5703125f;                // 8 bits: k * part1 is exact
  constexpr float kPio2Part2 = 4.837512969970703125e-4f;  // next bits
  constexpr float kPio2Part3 = 7.54978995489188216e-8f;   // the rest
  constexpr float kRoundMagic = 12582912.0f;              // 1.5 * 2^23: adding it rounds to an integer
  constexpr float S1 = -1.6666654611e-1f, S2 = 8.3321608736e-3f, S3 = -1.9515295891e-4f;
  constexpr float C1 = 4.166664568298827e-2f, C2 = -1.388731625493765e-3f, C3 = 2.443315711809948e-5f;
  constexpr float kLimit = 8192.0f;
  std::int32_t large = 0;  // an integer, as in the double version
  for (Eigen::Index i = 0; i < n; ++i) {
    const float xi = x[i];
    const float k = (xi * kTwoOverPi + kRoundMagic) - kRoundMagic;
    const float r = ((xi - k * kPio2Part1) - k * kPio2Part2) - k * kPio2Part3;  // |r| <= pi/4
    const float z = r * r;
    const float sin_r = r + z * r * (S1 + z * (S2 + z * S3));
    const float cos_r = 1.0f - 0.5f * z + z * z * (C1 + z * (C2 + z * C3));
    // Quadrant as in the double version: odd swaps sine and cosine, high negates both.
    const float m = k - 4.0f * ((k * 0.25f - 0.375f + kRoundMagic) - kRoundMagic);
    const float high = (m * 0.5f - 0.25f + kRoundMagic) - kRoundMagic;
    const float odd = m - 2.0f * high;
    const float sign = 1.0f - 2.0f * high;
    s[i] = sign * ((1.0f - odd) * sin_r + odd * cos_r);
    c[i] = sign * ((1.0f - odd) * cos_r - odd * sin_r);
    large += std::abs(xi) <= kLimit ? 0 : 1;
  }
  if (large == 0) return;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (std::abs(x[i]) <= kLimit) continue;
    s[i] = static_cast<float>(std::sin(static_cast<double>(x[i])));
    c[i] = static_cast<float>(std::cos(static_cast<double>(x[i])));
  }
}

}  // namespace s2kf::body
