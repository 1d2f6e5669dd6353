#include <s2kf/core/product_tiles.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

Eigen::MatrixXf product_test_matrix(Eigen::Index rows, Eigen::Index cols, std::mt19937& random) {
  std::normal_distribution<float> normal(0.0f, 10.0f);
  return Eigen::MatrixXf::NullaryExpr(rows, cols, [&] { return normal(random); });
}

// The sizes cross every tile edge: 1-row and 1-column remainders below 8 rows or the tile's
// columns, 8-row tiles, the overlapping last tile, and the tracker's 46 states and 150 coordinates.
const Eigen::Index kRows[] = {1, 3, 7, 8, 9, 12, 13, 16, 31, 32, 33, 46, 81, 150};
const Eigen::Index kSamples[] = {1, 5, 150, 301};
constexpr float kSentinel = 12345.0f;

}  // namespace

// Against the same product in double precision (each float product rounded once, so the sums
// agree to about the float epsilon times the number of terms), on blocks that sit inside larger
// matrices, so that the outer strides differ from the rows; every entry of the target outside the
// product keeps its sentinel value (a tile that adds anything there changes it).
TEST(ProductTiles, AddsTheProductOfOneMatrixWithAnotherTransposed) {
  std::mt19937 random(3);
  for (const Eigen::Index rows : kRows) {
    for (const Eigen::Index columns :
         {Eigen::Index(1), Eigen::Index(4), Eigen::Index(13), Eigen::Index(46)}) {
      for (const Eigen::Index samples : kSamples) {
        const Eigen::MatrixXf left_storage = product_test_matrix(rows + 3, samples + 2, random);
        const Eigen::MatrixXf right_storage = product_test_matrix(columns + 1, samples, random);
        const auto left = left_storage.block(2, 1, rows, samples);
        const auto right = right_storage.bottomRows(columns);
        Eigen::MatrixXf target_storage = Eigen::MatrixXf::Constant(rows + 2, columns + 3, kSentinel);
        auto target = target_storage.block(1, 2, rows, columns);
        const Eigen::MatrixXf start = product_test_matrix(rows, columns, random);
        target = start;

        s2kf::add_product_transposed(target, left, right);

        const Eigen::MatrixXd expected =
            start.cast<double>() + left.cast<double>() * right.cast<double>().transpose();
        const double scale = 100.0 * static_cast<double>(samples);  // the terms' magnitude times their count
        const double error = (target.cast<double>() - expected).cwiseAbs().maxCoeff();
        EXPECT_LT(error, 1e-5 * scale) << rows << " x " << columns << " over " << samples;
        int touched = 0;
        for (Eigen::Index j = 0; j < target_storage.cols(); ++j)
          for (Eigen::Index i = 0; i < target_storage.rows(); ++i) {
            const bool inside = i >= 1 && i < 1 + rows && j >= 2 && j < 2 + columns;
            if (!inside && target_storage(i, j) != kSentinel) ++touched;
          }
        EXPECT_EQ(touched, 0) << rows << " x " << columns << " over " << samples;
      }
    }
  }
}

// The lower half of C += A A^T; the strict upper half and everything around the block keep
// their sentinel value, so a tile that strays above the diagonal or past an edge is caught.
TEST(ProductTiles, AddsTheLowerHalfOfAMatrixTimesItsTranspose) {
  std::mt19937 random(5);
  for (const Eigen::Index rows : kRows) {
    for (const Eigen::Index samples : kSamples) {
      const Eigen::MatrixXf storage = product_test_matrix(rows + 4, samples + 1, random);
      const auto a = storage.block(1, 1, rows, samples);
      Eigen::MatrixXf target_storage = Eigen::MatrixXf::Constant(rows + 3, rows + 2, kSentinel);
      auto target = target_storage.block(2, 1, rows, rows);
      const Eigen::MatrixXf start = product_test_matrix(rows, rows, random);
      target.triangularView<Eigen::Lower>() = start;

      s2kf::add_self_product_lower(target, a);

      const Eigen::MatrixXd expected = start.cast<double>() + a.cast<double>() * a.cast<double>().transpose();
      const double scale = 100.0 * static_cast<double>(samples);
      double error = 0;
      int touched = 0;
      for (Eigen::Index j = 0; j < target_storage.cols(); ++j)
        for (Eigen::Index i = 0; i < target_storage.rows(); ++i) {
          const Eigen::Index r = i - 2, c = j - 1;
          const bool lower = r >= 0 && r < rows && c >= 0 && c < rows && r >= c;
          if (lower)
            error = std::max(error, std::abs(static_cast<double>(target_storage(i, j)) - expected(r, c)));
          else if (target_storage(i, j) != kSentinel)
            ++touched;
        }
      EXPECT_LT(error, 1e-5 * scale) << rows << " over " << samples;
      EXPECT_EQ(touched, 0) << rows << " over " << samples;
    }
  }
}

// No samples: nothing is added.
TEST(ProductTiles, AddsNothingOverNoSamples) {
  Eigen::MatrixXf a(5, 0), b(3, 0);
  Eigen::MatrixXf c = Eigen::MatrixXf::Constant(5, 3, 2.0f);
  s2kf::add_product_transposed(c, a, b);
  EXPECT_TRUE((c.array() == 2.0f).all());
  Eigen::MatrixXf s = Eigen::MatrixXf::Constant(5, 5, 2.0f);
  s2kf::add_self_product_lower(s, a);
  EXPECT_TRUE((s.array() == 2.0f).all());
}
