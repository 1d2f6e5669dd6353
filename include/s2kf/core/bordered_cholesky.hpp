/// @file
/// The bordered partial Cholesky factorisation: a symmetric positive-definite matrix A = L L^T and
/// the rows B beneath it solved against L^T, B L^-T, in one pass over one panel.
///
/// Every gain of the filter needs exactly this: the square-root gain with Cyy on top and Cyx^T
/// and the innovation as the border; the information form per group of measurements (L the factor
/// of D_g, the group's regression G_g^T and innovation as the border) and once more for the n x n
/// information matrix (the prior's factor S and the information vector as the border). Eigen's
/// LLT followed by a triangular solve does the same arithmetic, but at these sizes (20-200 rows)
/// both run far below the machine's multiply-add rate; this left-looking factorisation computes
/// four columns at a time over row tiles that stay in registers, about twice as fast as the two
/// calls together.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace s2kf {

/// The panel [A; B] (A size x size, lower half read; B border x size, any rows) is factorised in
/// place into [L; B L^-T]. The buffer only grows: once sized for the largest panel, factorising
/// smaller ones allocates nothing.
class BorderedCholesky {
 public:
  /// Rows of one register tile: four columns of this many doubles are 16 AVX-512 registers (the
  /// machine has 32) or 16 SSE/AVX registers of 8 doubles in all. The panel's rows are padded to
  /// a multiple of kPadRows only: the last rows go in tiles of that many.
#if defined(__AVX512F__)
  static constexpr Eigen::Index kTileRows = 32;
#else
  static constexpr Eigen::Index kTileRows = 8;
#endif
  static constexpr Eigen::Index kPadRows = 8;
  static constexpr Eigen::Index kTileColumns = 4;

  /// Prepares a panel for a `size` x `size` matrix with `border` rows beneath it.
  void resize(Eigen::Index size, Eigen::Index border) {
    size_ = size;
    rows_ = size + border;
    const Eigen::Index padded = padded_rows(rows_);
    if (storage_.rows() < padded || storage_.cols() < size)
      storage_.resize(std::max(storage_.rows(), padded), std::max(storage_.cols(), size));
  }

  /// The panel to fill before factorise(): rows [0, size) the matrix (only its lower half is
  /// read), rows [size, size + border) the border. After factorise(): L in the lower half of the
  /// top rows (the strict upper half unspecified) and B L^-T in the border rows.
  Eigen::Block<Eigen::MatrixXd> panel() { return storage_.topLeftCorner(rows_, size_); }

  /// Factorises the panel in place. False where the matrix is not positive definite (a pivot not
  /// above zero, or NaN); the panel is then unspecified.
  bool factorise() {
    const Eigen::Index stride = storage_.rows(), padded = padded_rows(rows_);
    // The tiles run over whole multiples of kPadRows rows: the rows below the border are zeroed,
    // and zero rows stay zero under the updates and the division by the pivots.
    storage_.block(rows_, 0, padded - rows_, size_).setZero();
    double* p = storage_.data();
    for (Eigen::Index j = 0; j < size_; j += kTileColumns) {
      const Eigen::Index width = std::min(kTileColumns, size_ - j);
      subtract_earlier_columns(p, stride, padded, j, width);
      if (!factorise_columns(p, stride, padded, j, width)) return false;
    }
    return true;
  }

 private:
  static Eigen::Index padded_rows(Eigen::Index rows) { return (rows + kPadRows - 1) / kPadRows * kPadRows; }

  /// Columns j..j+width of the panel, from the first tile holding row j down: minus the sum over
  /// the earlier columns k of p(j + c, k) p(:, k), four target columns per pass over a column k so
  /// that its tile is loaded once for all four. Rows above j of a tile receive values nobody reads.
  static void subtract_earlier_columns(double* p, Eigen::Index stride, Eigen::Index padded, Eigen::Index j,
                                       Eigen::Index width) {
    if (j == 0) return;
    double* target[kTileColumns];
    for (Eigen::Index c = 0; c < kTileColumns; ++c) target[c] = p + (j + std::min(c, width - 1)) * stride;
    Eigen::Index r = j / kPadRows * kPadRows;
    for (; r + kTileRows <= padded; r += kTileRows) subtract_tile<kTileRows>(p, stride, r, j, width, target);
    for (; r < padded; r += kPadRows) subtract_tile<kPadRows>(p, stride, r, j, width, target);
  }

  /// One tile of R rows from row r: the four columns' tile stays in registers while every earlier
  /// column passes once.
  template <Eigen::Index R>
  static void subtract_tile(const double* p, Eigen::Index stride, Eigen::Index r, Eigen::Index j,
                            Eigen::Index width, double* const* target) {
    constexpr Eigen::Index W = kTileColumns;
    using Tile = Eigen::Matrix<double, R, W>;
    using TileColumn = Eigen::Matrix<double, R, 1>;
    Tile tile;
    for (Eigen::Index c = 0; c < W; ++c) tile.col(c) = Eigen::Map<const TileColumn>(target[c] + r);
    for (Eigen::Index k = 0; k < j; ++k) {
      const double* column = p + k * stride;
      Eigen::Matrix<double, 1, W> factor;
      for (Eigen::Index c = 0; c < W; ++c) factor(c) = column[j + std::min(c, width - 1)];
      tile.noalias() -= Eigen::Map<const TileColumn>(column + r) * factor;
    }
    for (Eigen::Index c = 0; c < width; ++c) Eigen::Map<TileColumn>(target[c] + r) = tile.col(c);
  }

  /// The columns j..j+width among themselves: each minus the earlier ones of the group, then
  /// divided by the square root of its pivot.
  static bool factorise_columns(double* p, Eigen::Index stride, Eigen::Index padded, Eigen::Index j,
                                Eigen::Index width) {
    for (Eigen::Index c = 0; c < width; ++c) {
      double* column = p + (j + c) * stride;
      for (Eigen::Index k = 0; k < c; ++k) {
        const double* earlier = p + (j + k) * stride;
        const double factor = earlier[j + c];
        for (Eigen::Index i = j + c; i < padded; ++i) column[i] -= factor * earlier[i];
      }
      const double pivot = column[j + c];
      if (!(pivot > 0)) return false;  // NaN too
      const double l = std::sqrt(pivot), inverse = 1.0 / l;
      column[j + c] = l;
      for (Eigen::Index i = j + c + 1; i < padded; ++i) column[i] *= inverse;
    }
    return true;
  }

  Eigen::MatrixXd storage_;  // rows a multiple of kTileRows: the stride of every panel
  Eigen::Index size_ = 0, rows_ = 0;
};

}  // namespace s2kf
