/// @file
/// Register-tiled products for the filter's sample moments and its double-precision work:
/// C += alpha A B^T and the lower half of C += alpha A A^T, with A and B column-major (one column
/// per sample pair, sample or summed index), in float or double.
///
/// The moments of a step are products over the samples of tall, short matrices (150 measured
/// coordinates or 46 states by 150-301 samples). At these sizes Eigen's general products spend
/// much of their time packing their operands and run at about half the machine's multiply-add rate;
/// here a tile of C (32 rows by 12 columns of floats with AVX-512: 24 vector registers) stays in
/// registers while every sample passes once, reading A's column and B's row of the tile straight
/// from their matrices, so nothing is packed and nothing is allocated: about 1.5 times Eigen's
/// product at the tracker's sizes (docs/benchmarks.md). In double the same tiles make the filter's
/// rank updates, its sample draw S Z and the bordered Cholesky factorisation's updates. The tiles
/// are compiled for SSE2, AVX2 and AVX-512 and chosen at run time (core/instruction_set.hpp), in
/// the library and header-only alike; Eigen's own kernels run with the build's flags only.
#pragma once

#include <s2kf/core/instruction_set.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cstring>
#include <type_traits>

namespace s2kf {

namespace product_tiles_detail {

/// Register tiles per scalar and instruction set: a tile of C is kRows rows (two vectors of kLanes
/// scalars) by kColumns columns, so that its accumulators and one column of A fill the vector
/// registers (24 of 32 with AVX-512, 12 of 16 with AVX2 and SSE2).
template <typename Scalar, InstructionSet Set>
struct TileShape {
  static constexpr Eigen::Index kLanes = 16 / sizeof(Scalar), kRows = 2 * kLanes, kColumns = 6;
};
template <typename Scalar>
struct TileShape<Scalar, InstructionSet::avx2> {
  static constexpr Eigen::Index kLanes = 32 / sizeof(Scalar), kRows = 2 * kLanes, kColumns = 6;
};
template <typename Scalar>
struct TileShape<Scalar, InstructionSet::avx512> {
  static constexpr Eigen::Index kLanes = 64 / sizeof(Scalar), kRows = 2 * kLanes, kColumns = 12;
};

/// GCC/Clang vectors of L scalars: arithmetic on them compiles to the instructions of the
/// function's target (several registers' worth where L is wider than the target's registers).
template <typename Scalar, Eigen::Index L>
struct VectorOf {
  typedef Scalar type __attribute__((vector_size(L * sizeof(Scalar))));
};

/// Where an operand lies: column-major with an outer stride (any Eigen block of a matrix).
template <typename Scalar>
struct OperandOf {
  const Scalar* data;
  Eigen::Index stride;
};
using Operand = OperandOf<float>;

/// One product C(first_row.., ..) += alpha A B^T over `samples` columns of A and B. With `lower`
/// only C's lower half is written; with `a_lower_triangular` A's entries above its diagonal are
/// zero (a row tile then sums only up to its last row's column: the same sums, fewer terms).
template <typename Scalar>
struct Product {
  OperandOf<Scalar> a, b;
  Eigen::Index samples;
  Scalar* c;
  Eigen::Index c_stride, rows, columns;
  bool lower = false;
  Scalar alpha = 1;
  Eigen::Index first_row = 0;
  bool a_lower_triangular = false;
};

/// The sum over the samples t of A(r..r+R, t) B(j..j+W, t) into `tile` (column-major, R x W), with
/// vectors of L scalars (R a multiple of L; R = 1 in scalars). Each entry is summed over t in order
/// with one multiply-add per sample, whatever L, so the variants agree where they all fuse them.
template <typename Scalar, Eigen::Index L, Eigen::Index R, Eigen::Index W>
S2KF_ALWAYS_INLINE void sum_tile(OperandOf<Scalar> a, OperandOf<Scalar> b, Eigen::Index samples,
                                 Eigen::Index r, Eigen::Index j, Scalar* tile) {
  if constexpr (R == 1) {
    Scalar sums[W] = {};
    for (Eigen::Index t = 0; t < samples; ++t) {
      const Scalar a_value = a.data[t * a.stride + r];
      const Scalar* b_column = b.data + t * b.stride + j;
#pragma GCC unroll 16
      for (Eigen::Index w = 0; w < W; ++w) sums[w] += a_value * b_column[w];
    }
    for (Eigen::Index w = 0; w < W; ++w) tile[w] = sums[w];
  } else {
    using Vector = typename VectorOf<Scalar, L>::type;
    constexpr Eigen::Index P = R / L;
    static_assert(P * L == R, "product tiles: the rows of a tile are whole vectors");
    Vector sums[W][P];
#pragma GCC unroll 16
    for (Eigen::Index w = 0; w < W; ++w)
#pragma GCC unroll 4
      for (Eigen::Index p = 0; p < P; ++p) sums[w][p] = Vector{};
    for (Eigen::Index t = 0; t < samples; ++t) {
      const Scalar* a_column = a.data + t * a.stride + r;
      const Scalar* b_column = b.data + t * b.stride + j;
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

/// C(r..r+R, j..j+W) += alpha times the sum over the samples t of A(r..r+R, t) B(j..j+W, t),
/// written only from row `row_from` and column `column_from` on (a tile that overlaps its
/// neighbour at the edge of C); with `lower`, not above C's diagonal either.
template <typename Scalar, Eigen::Index L, Eigen::Index R, Eigen::Index W>
S2KF_ALWAYS_INLINE void add_tile(const Product<Scalar>& p, Eigen::Index r, Eigen::Index j,
                                 Eigen::Index row_from, Eigen::Index column_from) {
  Scalar tile[R * W];
  // A lower triangular A has only zeros beyond column r + R - 1 in these rows.
  const Eigen::Index samples = p.a_lower_triangular ? std::min(p.samples, r + R) : p.samples;
  sum_tile<Scalar, L, R, W>(p.a, p.b, samples, r, j, tile);
  for (Eigen::Index w = std::max<Eigen::Index>(0, column_from - j); w < W; ++w) {
    Scalar* target = p.c + (j + w) * p.c_stride;
    const Eigen::Index from = std::max({r, row_from, p.lower ? j + w : r});
    if (p.alpha == Scalar(1))
      for (Eigen::Index i = from; i < r + R; ++i) target[i] += tile[w * R + i - r];
    else
      for (Eigen::Index i = from; i < r + R; ++i) target[i] += p.alpha * tile[w * R + i - r];
  }
}

/// The columns j..j+W of C (written from column `column_from`), rows `first` to `rows`: tiles of
/// Shape::kRows rows, then of E = min(kRows, 8); the last few rows by an E-row tile that overlaps
/// the one before.
template <typename Scalar, typename Shape, Eigen::Index W>
S2KF_ALWAYS_INLINE void add_column_block(const Product<Scalar>& p, Eigen::Index first, Eigen::Index j,
                                         Eigen::Index column_from) {
  constexpr Eigen::Index kRows = Shape::kRows, L = Shape::kLanes;
  constexpr Eigen::Index E = kRows < 8 ? kRows : 8;  // rows of an edge tile
  constexpr Eigen::Index LE = L < E ? L : E;         // its vectors' lanes
  const Eigen::Index rows = p.rows;
  Eigen::Index r = first;
  for (; r + kRows <= rows; r += kRows) add_tile<Scalar, L, kRows, W>(p, r, j, r, column_from);
  if constexpr (kRows > E)
    for (; r + E <= rows; r += E) add_tile<Scalar, LE, E, W>(p, r, j, r, column_from);
  if (r == rows) return;
  if (rows >= E) {
    add_tile<Scalar, LE, E, W>(p, rows - E, j, r, column_from);
  } else {
    for (; r < rows; ++r) add_tile<Scalar, 1, 1, W>(p, r, j, r, column_from);
  }
}

/// The product in the tiles of instruction set Set: blocks of Shape::kColumns columns, the last
/// ones by a block that overlaps the one before; fewer columns than that in blocks of 4 (the
/// bordered Cholesky factorisation's four columns), then one by one.
template <typename Scalar, InstructionSet Set>
S2KF_ALWAYS_INLINE void add_products_with(const Product<Scalar>& p) {
  using Shape = TileShape<Scalar, Set>;
  // With `lower` a column block starts at its first row on or below the diagonal.
  const auto first = [&p](Eigen::Index j) { return p.lower ? std::max(j, p.first_row) : p.first_row; };
  constexpr Eigen::Index W = Shape::kColumns;
  const Eigen::Index columns = p.columns;
  Eigen::Index j = 0;
  for (; j + W <= columns; j += W) add_column_block<Scalar, Shape, W>(p, first(j), j, j);
  if (j == columns) return;
  if (columns >= W) {  // the last columns: a block that overlaps the one before
    const Eigen::Index start = columns - W;
    add_column_block<Scalar, Shape, W>(p, first(start), start, j);
    return;
  }
  for (; j + 4 <= columns; j += 4) add_column_block<Scalar, Shape, 4>(p, first(j), j, j);
  if (j == columns) return;
  if (columns >= 4) {
    add_column_block<Scalar, Shape, 4>(p, first(columns - 4), columns - 4, j);
    return;
  }
  for (; j < columns; ++j) add_column_block<Scalar, Shape, 1>(p, first(j), j, j);
}

/// add_products_with for the variant run_with_instruction_set picks.
template <typename Scalar>
struct AddProducts {
  const Product<Scalar>& product;
  template <typename Tag>
  S2KF_ALWAYS_INLINE void operator()(Tag) const {
    add_products_with<Scalar, Tag::value>(product);
  }
};

/// The product with the variant `set` (the one in use unless a test asks for another).
template <typename Scalar>
void add_products(const Product<Scalar>& product, InstructionSet set = active_instruction_set()) {
  run_with_instruction_set(set, AddProducts<Scalar>{product});
}

/// C (rows x columns, with `lower` only its lower half) += A B^T over `samples` columns.
template <typename Scalar>
void add_products(OperandOf<Scalar> a, OperandOf<Scalar> b, Eigen::Index samples, Scalar* c,
                  Eigen::Index c_stride, Eigen::Index rows, Eigen::Index columns, bool lower,
                  InstructionSet set = active_instruction_set()) {
  Product<Scalar> product{a, b, samples, c, c_stride, rows, columns};
  product.lower = lower;
  add_products(product, set);
}
inline void add_products(Operand a, Operand b, Eigen::Index samples, float* c, Eigen::Index c_stride,
                         Eigen::Index rows, Eigen::Index columns, bool lower,
                         InstructionSet set = active_instruction_set()) {
  add_products<float>(a, b, samples, c, c_stride, rows, columns, lower, set);
}

template <typename Matrix>
OperandOf<typename Matrix::Scalar> operand(const Matrix& m) {
  static_assert(!Matrix::IsRowMajor, "product tiles: the operands must be column-major");
  eigen_assert(m.innerStride() == 1);
  return {m.data(), m.outerStride()};
}

template <typename Target, typename Left, typename Right>
Product<typename std::decay_t<Target>::Scalar> product_of(Target& c, const Left& a, const Right& b) {
  using Scalar = typename std::decay_t<Target>::Scalar;
  static_assert(
      std::is_same_v<Scalar, typename Left::Scalar> && std::is_same_v<Scalar, typename Right::Scalar>,
      "product tiles: one scalar type");
  eigen_assert(a.rows() == c.rows() && b.rows() == c.cols() && a.cols() == b.cols());
  eigen_assert(c.innerStride() == 1);
  return Product<Scalar>{operand(a), operand(b), a.cols(), c.data(), c.outerStride(), c.rows(), c.cols()};
}

}  // namespace product_tiles_detail

/// c += alpha a b^T for column-major float or double matrices (blocks included): a is c.rows() x k,
/// b c.cols() x k.
template <typename Target, typename Left, typename Right>
void add_product_transposed(Target&& c, const Left& a, const Right& b,
                            typename std::decay_t<Target>::Scalar alpha = 1) {
  auto product = product_tiles_detail::product_of(c, a, b);
  product.alpha = alpha;
  product_tiles_detail::add_products(product);
}

/// c += l b^T with l lower triangular: l's entries above its diagonal must be zero (a tile reads
/// them up to its last row); l is c.rows() x k, b c.cols() x k.
template <typename Target, typename Left, typename Right>
void add_triangular_product_transposed(Target&& c, const Left& l, const Right& b) {
  auto product = product_tiles_detail::product_of(c, l, b);
  product.a_lower_triangular = true;
  product_tiles_detail::add_products(product);
}

/// The lower half of c += alpha a a^T (the strict upper half is not touched): a is c.rows() x k.
template <typename Target, typename Left>
void add_self_product_lower(Target&& c, const Left& a, typename std::decay_t<Target>::Scalar alpha = 1) {
  eigen_assert(c.rows() == c.cols());
  auto product = product_tiles_detail::product_of(c, a, a);
  product.lower = true;
  product.alpha = alpha;
  product_tiles_detail::add_products(product);
}

}  // namespace s2kf
