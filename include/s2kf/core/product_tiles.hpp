/// @file
/// Register-tiled single-precision products for the filter's sample moments: C += A B^T and the
/// lower half of C += A A^T, with A and B column-major (one column per sample pair or sample).
///
/// The moments of a step are products over the samples of tall, short matrices (150 measured
/// coordinates or 46 states by 150-301 samples). At these sizes Eigen's general products spend
/// much of their time packing their operands and run at about half the machine's multiply-add rate;
/// here a tile of C (32 rows by 12 columns with AVX-512: 24 vector registers) stays in registers
/// while every sample passes once, reading A's column and B's row of the tile straight from their
/// matrices, so nothing is packed and nothing is allocated: about 1.5 times Eigen's product at the
/// tracker's sizes (docs/benchmarks.md). The tiles are compiled for SSE2, AVX2 and AVX-512 and
/// chosen at run time (core/instruction_set.hpp).
#pragma once

#include <s2kf/core/instruction_set.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cstring>

namespace s2kf {

namespace product_tiles_detail {

/// Register tiles per instruction set: a tile of C is kRows rows (two vectors of kLanes floats)
/// by kColumns columns, so that its accumulators and one column of A fill the vector registers
/// (24 of 32 with AVX-512, 12 of 16 with AVX2 and SSE2).
template <InstructionSet Set>
struct TileShape {
  static constexpr Eigen::Index kLanes = 4, kRows = 8, kColumns = 6;
};
template <>
struct TileShape<InstructionSet::avx2> {
  static constexpr Eigen::Index kLanes = 8, kRows = 16, kColumns = 6;
};
template <>
struct TileShape<InstructionSet::avx512> {
  static constexpr Eigen::Index kLanes = 16, kRows = 32, kColumns = 12;
};

/// GCC/Clang vectors of L floats: arithmetic on them compiles to the instructions of the function's
/// target (several registers' worth where L is wider than the target's registers).
template <Eigen::Index L>
struct FloatVector;
template <>
struct FloatVector<4> {
  typedef float type __attribute__((vector_size(16)));
};
template <>
struct FloatVector<8> {
  typedef float type __attribute__((vector_size(32)));
};
template <>
struct FloatVector<16> {
  typedef float type __attribute__((vector_size(64)));
};

/// Where the operands lie: column-major with an outer stride (any Eigen block of a float matrix).
struct Operand {
  const float* data;
  Eigen::Index stride;
};

/// The sum over the samples t of A(r..r+R, t) B(j..j+W, t) into `tile` (column-major, R x W), with
/// vectors of L floats (R a multiple of L; R = 1 in scalars). Each entry is summed over t in order
/// with one multiply-add per sample, whatever L, so the variants agree where they all fuse them.
template <Eigen::Index L, Eigen::Index R, Eigen::Index W>
S2KF_ALWAYS_INLINE void sum_tile(Operand a, Operand b, Eigen::Index samples, Eigen::Index r, Eigen::Index j,
                                 float* tile) {
  if constexpr (R == 1) {
    float sums[W] = {};
    for (Eigen::Index t = 0; t < samples; ++t) {
      const float a_value = a.data[t * a.stride + r];
      const float* b_column = b.data + t * b.stride + j;
#pragma GCC unroll 16
      for (Eigen::Index w = 0; w < W; ++w) sums[w] += a_value * b_column[w];
    }
    for (Eigen::Index w = 0; w < W; ++w) tile[w] = sums[w];
  } else {
    using Vector = typename FloatVector<L>::type;
    constexpr Eigen::Index P = R / L;
    static_assert(P * L == R, "product tiles: the rows of a tile are whole vectors");
    Vector sums[W][P];
#pragma GCC unroll 16
    for (Eigen::Index w = 0; w < W; ++w)
#pragma GCC unroll 4
      for (Eigen::Index p = 0; p < P; ++p) sums[w][p] = Vector{};
    for (Eigen::Index t = 0; t < samples; ++t) {
      const float* a_column = a.data + t * a.stride + r;
      const float* b_column = b.data + t * b.stride + j;
      Vector column[P];
#pragma GCC unroll 4
      for (Eigen::Index p = 0; p < P; ++p) std::memcpy(&column[p], a_column + p * L, sizeof(Vector));
#pragma GCC unroll 16
      for (Eigen::Index w = 0; w < W; ++w) {
        const Vector b_value = b_column[w] - Vector{};  // every lane b (x - 0 is exact)
#pragma GCC unroll 4
        for (Eigen::Index p = 0; p < P; ++p) sums[w][p] += column[p] * b_value;
      }
    }
#pragma GCC unroll 16
    for (Eigen::Index w = 0; w < W; ++w)
#pragma GCC unroll 4
      for (Eigen::Index p = 0; p < P; ++p) std::memcpy(tile + w * R + p * L, &sums[w][p], sizeof(Vector));
  }
}

/// C(r..r+R, j..j+W) += sum over the samples t of A(r..r+R, t) B(j..j+W, t), written only from
/// row `row_from` and column `column_from` on (a tile that overlaps its neighbour at the edge of
/// C); with `lower`, not above C's diagonal either.
template <Eigen::Index L, Eigen::Index R, Eigen::Index W>
S2KF_ALWAYS_INLINE void add_tile(Operand a, Operand b, Eigen::Index samples, float* c, Eigen::Index c_stride,
                                 Eigen::Index r, Eigen::Index j, Eigen::Index row_from,
                                 Eigen::Index column_from, bool lower) {
  float tile[R * W];
  sum_tile<L, R, W>(a, b, samples, r, j, tile);
  for (Eigen::Index w = std::max<Eigen::Index>(0, column_from - j); w < W; ++w) {
    float* target = c + (j + w) * c_stride;
    const Eigen::Index from = std::max({r, row_from, lower ? j + w : r});
    for (Eigen::Index i = from; i < r + R; ++i) target[i] += tile[w * R + i - r];
  }
}

/// The columns j..j+W of C (written from column `column_from`), rows `first` to `rows`: tiles of
/// Shape::kRows rows, then of 8; the last few rows by an 8-row tile that overlaps the one before.
template <typename Shape, Eigen::Index W>
S2KF_ALWAYS_INLINE void add_column_block(Operand a, Operand b, Eigen::Index samples, float* c,
                                         Eigen::Index c_stride, Eigen::Index first, Eigen::Index rows,
                                         Eigen::Index j, Eigen::Index column_from, bool lower) {
  constexpr Eigen::Index kRows = Shape::kRows, L = Shape::kLanes;
  constexpr Eigen::Index L8 = L < 8 ? L : 8;  // vectors of an 8-row tile
  Eigen::Index r = first;
  for (; r + kRows <= rows; r += kRows)
    add_tile<L, kRows, W>(a, b, samples, c, c_stride, r, j, r, column_from, lower);
  if constexpr (kRows > 8)
    for (; r + 8 <= rows; r += 8) add_tile<L8, 8, W>(a, b, samples, c, c_stride, r, j, r, column_from, lower);
  if (r == rows) return;
  if (rows >= 8) {
    add_tile<L8, 8, W>(a, b, samples, c, c_stride, rows - 8, j, r, column_from, lower);
  } else {
    for (; r < rows; ++r) add_tile<1, 1, W>(a, b, samples, c, c_stride, r, j, r, column_from, lower);
  }
}

/// C (rows x columns, with `lower` only its lower half) += A B^T over `samples` columns, in the
/// tiles of instruction set Set.
template <InstructionSet Set>
S2KF_ALWAYS_INLINE void add_products_with(Operand a, Operand b, Eigen::Index samples, float* c,
                                          Eigen::Index c_stride, Eigen::Index rows, Eigen::Index columns,
                                          bool lower) {
  using Shape = TileShape<Set>;
  // With `lower` a column block starts at its first row on or below the diagonal.
  const auto first = [lower](Eigen::Index j) { return lower ? j : Eigen::Index(0); };
  constexpr Eigen::Index W = Shape::kColumns;
  Eigen::Index j = 0;
  for (; j + W <= columns; j += W)
    add_column_block<Shape, W>(a, b, samples, c, c_stride, first(j), rows, j, j, lower);
  if (j == columns) return;
  if (columns >= W) {  // the last columns: a block that overlaps the one before
    const Eigen::Index start = columns - W;
    add_column_block<Shape, W>(a, b, samples, c, c_stride, first(start), rows, start, j, lower);
  } else {
    for (; j < columns; ++j)
      add_column_block<Shape, 1>(a, b, samples, c, c_stride, first(j), rows, j, j, lower);
  }
}

/// add_products_with for the variant run_with_instruction_set picks.
struct AddProducts {
  Operand a, b;
  Eigen::Index samples;
  float* c;
  Eigen::Index c_stride, rows, columns;
  bool lower;
  template <typename Tag>
  S2KF_ALWAYS_INLINE void operator()(Tag) const {
    add_products_with<Tag::value>(a, b, samples, c, c_stride, rows, columns, lower);
  }
};

/// C (rows x columns, with `lower` only its lower half) += A B^T over `samples` columns.
inline void add_products(Operand a, Operand b, Eigen::Index samples, float* c, Eigen::Index c_stride,
                         Eigen::Index rows, Eigen::Index columns, bool lower,
                         InstructionSet set = active_instruction_set()) {
  run_with_instruction_set(set, AddProducts{a, b, samples, c, c_stride, rows, columns, lower});
}

template <typename Matrix>
Operand operand(const Matrix& m) {
  static_assert(!Matrix::IsRowMajor, "product tiles: the operands must be column-major");
  eigen_assert(m.innerStride() == 1);
  return Operand{m.data(), m.outerStride()};
}

}  // namespace product_tiles_detail

/// c += a b^T for column-major float matrices (blocks included): a is c.rows() x k, b c.cols() x k.
template <typename Target, typename Left, typename Right>
void add_product_transposed(Target&& c, const Left& a, const Right& b) {
  eigen_assert(a.rows() == c.rows() && b.rows() == c.cols() && a.cols() == b.cols());
  eigen_assert(c.innerStride() == 1);
  product_tiles_detail::add_products(product_tiles_detail::operand(a), product_tiles_detail::operand(b),
                                     a.cols(), c.data(), c.outerStride(), c.rows(), c.cols(), false);
}

/// The lower half of c += a a^T (the strict upper half is not touched): a is c.rows() x k.
template <typename Target, typename Left>
void add_self_product_lower(Target&& c, const Left& a) {
  eigen_assert(c.rows() == c.cols() && a.rows() == c.rows());
  eigen_assert(c.innerStride() == 1);
  const auto operand = product_tiles_detail::operand(a);
  product_tiles_detail::add_products(operand, operand, a.cols(), c.data(), c.outerStride(), c.rows(),
                                     c.cols(), true);
}

}  // namespace s2kf
