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
/// tracker's sizes (docs/benchmarks.md).
#pragma once

#include <Eigen/Core>

#include <algorithm>

namespace s2kf {

namespace product_tiles_detail {

#if defined(__AVX512F__)
inline constexpr Eigen::Index kTileRows = 32;  // two 16-float registers per column
inline constexpr Eigen::Index kTileColumns = 12;
#elif defined(__AVX__)
inline constexpr Eigen::Index kTileRows = 16;  // two 8-float registers per column
inline constexpr Eigen::Index kTileColumns = 6;
#else
inline constexpr Eigen::Index kTileRows = 8;  // two 4-float registers per column
inline constexpr Eigen::Index kTileColumns = 6;
#endif

/// Where the operands lie: column-major with an outer stride (any Eigen block of a float matrix).
struct Operand {
  const float* data;
  Eigen::Index stride;
};

/// C(r..r+R, j..j+W) += sum over the samples t of A(r..r+R, t) B(j..j+W, t), written only from
/// row `row_from` and column `column_from` on (a tile that overlaps its neighbour at the edge of
/// C); with `lower`, not above C's diagonal either.
template <Eigen::Index R, Eigen::Index W>
void add_tile(Operand a, Operand b, Eigen::Index samples, float* c, Eigen::Index c_stride, Eigen::Index r,
              Eigen::Index j, Eigen::Index row_from, Eigen::Index column_from, bool lower) {
  using Column = Eigen::Matrix<float, R, 1>;
  Eigen::Matrix<float, R, W> tile = Eigen::Matrix<float, R, W>::Zero();
  for (Eigen::Index t = 0; t < samples; ++t) {
    const float* a_column = a.data + t * a.stride + r;
    const float* b_column = b.data + t * b.stride + j;
    Eigen::Matrix<float, 1, W> row;
    for (Eigen::Index w = 0; w < W; ++w) row(w) = b_column[w];
    tile.noalias() += Eigen::Map<const Column>(a_column) * row;
  }
  for (Eigen::Index w = std::max<Eigen::Index>(0, column_from - j); w < W; ++w) {
    float* target = c + (j + w) * c_stride;
    const Eigen::Index from = std::max({r, row_from, lower ? j + w : r});
    for (Eigen::Index i = from; i < r + R; ++i) target[i] += tile(i - r, w);
  }
}

/// The columns j..j+W of C (written from column `column_from`), rows `first` to `rows`: tiles of
/// kTileRows rows, then of 8; the last few rows by an 8-row tile that overlaps the one before.
template <Eigen::Index W>
void add_column_block(Operand a, Operand b, Eigen::Index samples, float* c, Eigen::Index c_stride,
                      Eigen::Index first, Eigen::Index rows, Eigen::Index j, Eigen::Index column_from,
                      bool lower) {
  Eigen::Index r = first;
  for (; r + kTileRows <= rows; r += kTileRows)
    add_tile<kTileRows, W>(a, b, samples, c, c_stride, r, j, r, column_from, lower);
  if constexpr (kTileRows > 8)
    for (; r + 8 <= rows; r += 8) add_tile<8, W>(a, b, samples, c, c_stride, r, j, r, column_from, lower);
  if (r == rows) return;
  if (rows >= 8) {
    add_tile<8, W>(a, b, samples, c, c_stride, rows - 8, j, r, column_from, lower);
  } else {
    for (; r < rows; ++r) add_tile<1, W>(a, b, samples, c, c_stride, r, j, r, column_from, lower);
  }
}

/// C (rows x columns, with `lower` only its lower half) += A B^T over `samples` columns.
inline void add_products(Operand a, Operand b, Eigen::Index samples, float* c, Eigen::Index c_stride,
                         Eigen::Index rows, Eigen::Index columns, bool lower) {
  // With `lower` a column block starts at its first row on or below the diagonal.
  const auto first = [lower](Eigen::Index j) { return lower ? j : Eigen::Index(0); };
  constexpr Eigen::Index W = kTileColumns;
  Eigen::Index j = 0;
  for (; j + W <= columns; j += W)
    add_column_block<W>(a, b, samples, c, c_stride, first(j), rows, j, j, lower);
  if (j == columns) return;
  if (columns >= W) {  // the last columns: a block that overlaps the one before
    const Eigen::Index start = columns - W;
    add_column_block<W>(a, b, samples, c, c_stride, first(start), rows, start, j, lower);
  } else {
    for (; j < columns; ++j) add_column_block<1>(a, b, samples, c, c_stride, first(j), rows, j, j, lower);
  }
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
