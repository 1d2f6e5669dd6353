#include <s2kf/core/bordered_cholesky.hpp>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include <limits>
#include <random>

namespace {

// A random symmetric positive-definite matrix with eigenvalues between about 1 and 1 + size.
Eigen::MatrixXd bordered_test_spd(Eigen::Index size, std::mt19937& random) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd a(size, size + 3);
  for (Eigen::Index j = 0; j < a.cols(); ++j)
    for (Eigen::Index i = 0; i < size; ++i) a(i, j) = normal(random);
  Eigen::MatrixXd spd = a * a.transpose() / static_cast<double>(a.cols());
  spd.diagonal().array() += 1.0;
  return spd;
}

Eigen::MatrixXd bordered_test_matrix(Eigen::Index rows, Eigen::Index cols, std::mt19937& random) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd b(rows, cols);
  for (Eigen::Index j = 0; j < cols; ++j)
    for (Eigen::Index i = 0; i < rows; ++i) b(i, j) = 10.0 * normal(random);
  return b;
}

}  // namespace

// Against Eigen's LLT and triangular solve, for sizes below, at and across the register tile's
// four columns and its 8 or 32 rows, with borders of none to several tiles.
TEST(BorderedCholesky, GivesTheCholeskyFactorAndTheBorderSolvedAgainstItsTranspose) {
  std::mt19937 random(7);
  s2kf::BorderedCholesky bordered;
  for (const Eigen::Index size : {1, 2, 3, 4, 5, 7, 8, 9, 31, 32, 33, 46, 81}) {
    for (const Eigen::Index border : {0, 1, 5, 47}) {
      const Eigen::MatrixXd a = bordered_test_spd(size, random);
      const Eigen::MatrixXd b = bordered_test_matrix(border, size, random);
      bordered.resize(size, border);
      auto panel = bordered.panel();
      ASSERT_EQ(panel.rows(), size + border);
      ASSERT_EQ(panel.cols(), size);
      panel.setConstant(std::numeric_limits<double>::quiet_NaN());  // only the lower half is read
      panel.topRows(size).triangularView<Eigen::Lower>() = a;
      panel.bottomRows(border) = b;
      ASSERT_TRUE(bordered.factorise()) << size << " + " << border;

      const Eigen::LLT<Eigen::MatrixXd> reference(a);
      const Eigen::MatrixXd l = reference.matrixL();
      Eigen::MatrixXd solved = b;
      if (border > 0) reference.matrixU().solveInPlace<Eigen::OnTheRight>(solved);  // Eigen: not on 0 rows
      const Eigen::MatrixXd factor = panel.topRows(size).triangularView<Eigen::Lower>();
      EXPECT_LT((factor - l).norm(), 1e-13 * l.norm()) << size << " + " << border;
      if (border > 0) {
        EXPECT_LT((panel.bottomRows(border) - solved).norm(), 1e-12 * solved.norm())
            << size << " + " << border;
      }
      // And the defining identities, independently of Eigen's factorisation.
      EXPECT_LT((factor * factor.transpose() - a).norm(), 1e-13 * a.norm());
      if (border > 0) {
        EXPECT_LT((panel.bottomRows(border) * factor.transpose() - b).norm(), 1e-12 * b.norm());
      }
    }
  }
}

TEST(BorderedCholesky, ASmallerPanelAfterALargerOneIsFactorisedAlike) {
  std::mt19937 random(11);
  s2kf::BorderedCholesky bordered;
  const Eigen::MatrixXd big = bordered_test_spd(40, random);
  bordered.resize(40, 20);
  bordered.panel().topRows(40) = big;
  bordered.panel().bottomRows(20) = bordered_test_matrix(20, 40, random);
  ASSERT_TRUE(bordered.factorise());
  // The buffer keeps the larger panel's values below and beside the smaller one.
  const Eigen::MatrixXd a = bordered_test_spd(6, random);
  const Eigen::MatrixXd b = bordered_test_matrix(3, 6, random);
  bordered.resize(6, 3);
  bordered.panel().topRows(6) = a;
  bordered.panel().bottomRows(3) = b;
  ASSERT_TRUE(bordered.factorise());
  const Eigen::MatrixXd factor = bordered.panel().topRows(6).triangularView<Eigen::Lower>();
  EXPECT_LT((factor * factor.transpose() - a).norm(), 1e-13 * a.norm());
  EXPECT_LT((bordered.panel().bottomRows(3) * factor.transpose() - b).norm(), 1e-12 * b.norm());
}

TEST(BorderedCholesky, RefusesAMatrixThatIsNotPositiveDefinite) {
  s2kf::BorderedCholesky bordered;
  // Eigenvalues 3 and -1 (indefinite), then a zero pivot at the fifth column, then a NaN.
  Eigen::MatrixXd indefinite(2, 2);
  indefinite << 1, 2, 2, 1;
  bordered.resize(2, 1);
  bordered.panel().topRows(2) = indefinite;
  bordered.panel().bottomRows(1).setOnes();
  EXPECT_FALSE(bordered.factorise());

  Eigen::MatrixXd singular = Eigen::MatrixXd::Identity(6, 6);
  singular(4, 4) = 0;
  bordered.resize(6, 0);
  bordered.panel() = singular;
  EXPECT_FALSE(bordered.factorise());

  Eigen::MatrixXd with_nan = Eigen::MatrixXd::Identity(6, 6);
  with_nan(5, 2) = std::numeric_limits<double>::quiet_NaN();
  bordered.resize(6, 2);
  bordered.panel().topRows(6) = with_nan;
  bordered.panel().bottomRows(2).setOnes();
  EXPECT_FALSE(bordered.factorise());
}
