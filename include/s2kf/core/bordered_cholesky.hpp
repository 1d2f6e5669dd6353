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
/// four columns at a time over row tiles that stay in registers (core/product_tiles.hpp, compiled for
/// the processor's instruction set), about twice as fast as the two calls together.
#pragma once

#include <s2kf/core/product_tiles.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace s2kf {

/// The panel [A; B] (A size x size, lower half read; B border x size, any rows) is factorised in
/// place into [L; B L^-T]. The buffer only grows: once sized for the largest panel, factorising
/// smaller ones allocates nothing.
class BorderedCholesky {
 public:
  /// The panel's rows are padded to a multiple of kPadRows (zero rows beneath the border), so that
  /// the column loops run over whole vectors.
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

  /// Columns j..j+width of the panel, from the first padded row group holding row j down: minus the
  /// sum over the earlier columns k of p(j + c, k) p(:, k), in register tiles compiled for the
  /// processor's instruction set (core/product_tiles.hpp): [L; B](r.., j..) -= P(r.., :j) P(j.., :j)^T.
  /// Rows above j of a tile receive values nobody reads.
  static void subtract_earlier_columns(double* p, Eigen::Index stride, Eigen::Index padded, Eigen::Index j,
                                       Eigen::Index width) {
    if (j == 0) return;
    product_tiles_detail::Product<double> product{{p, stride}, {p + j, stride}, j,    p + j * stride,
                                                  stride,      padded,          width};
    product.alpha = -1;
    product.first_row = j / kPadRows * kPadRows;
    product_tiles_detail::add_products(product);
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

  Eigen::MatrixXd storage_;  // rows a multiple of kPadRows: the stride of every panel
  Eigen::Index size_ = 0, rows_ = 0;
};

}  // namespace s2kf
