#include <s2kf/geometry/nearest_point_tree.hpp>

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace {

using s2kf::geometry::NearestPointTree;

// Brute force: the first column at the smallest squared distance below the bound.
NearestPointTree::Hit scan(const Eigen::Matrix3Xd& points, const Eigen::Vector3d& q, double below) {
  NearestPointTree::Hit best;
  for (Eigen::Index k = 0; k < points.cols(); ++k) {
    const double d2 = (points.col(k) - q).squaredNorm();
    if (d2 < below && d2 < best.squared_distance) best = {k, d2};
  }
  return best;
}

TEST(NearestPointTree, FindsWhatAScanFindsWithTiesAndBounds) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-500, 500);
  for (const Eigen::Index count : {1, 2, 3, 10, 257}) {
    Eigen::Matrix3Xd points(3, count);
    for (Eigen::Index k = 0; k < count; ++k)
      for (int r = 0; r < 3; ++r) points(r, k) = coordinate(random);
    // Duplicates and points on a grid give ties, which the lowest index must win.
    for (Eigen::Index k = count / 2; k + 1 < count; k += 3) points.col(k + 1) = points.col(k / 2);
    for (Eigen::Index k = 0; k < count; k += 5) points.col(k) = (points.col(k) / 100).array().round() * 100;
    const NearestPointTree tree(points);
    EXPECT_EQ(tree.size(), count);
    for (int trial = 0; trial < 2000; ++trial) {
      Eigen::Vector3d q;
      for (int r = 0; r < 3; ++r) q(r) = coordinate(random);
      if (trial % 4 == 0) q = (q / 100).array().round() * 100 + Eigen::Array3d(50, 0, 0);  // equidistant
      if (trial % 7 == 0) q = points.col(trial % count);                                   // on a point
      for (const double below : {std::numeric_limits<double>::infinity(), 150.0 * 150.0, 20.0 * 20.0}) {
        const NearestPointTree::Hit expected = scan(points, q, below);
        const NearestPointTree::Hit found = tree.nearest(q, below);
        ASSERT_EQ(found.index, expected.index)
            << "count " << count << " trial " << trial << " below " << below;
        // To 4 ulps: the library's copy may fuse the multiply-adds the scan's does not.
        EXPECT_DOUBLE_EQ(found.squared_distance, expected.squared_distance);
      }
    }
  }
}

TEST(NearestPointTree, NothingNearEnoughAndAnEmptyTreeGiveNoHit) {
  Eigen::Matrix3Xd points(3, 2);
  points << 0, 10, 0, 0, 0, 0;
  const NearestPointTree tree(points);
  EXPECT_EQ(tree.nearest(Eigen::Vector3d(5, 0, 0)).index, 0);  // a tie: the lower index
  EXPECT_EQ(tree.nearest(Eigen::Vector3d(9, 0, 0)).index, 1);
  const NearestPointTree::Hit none = tree.nearest(Eigen::Vector3d(5, 0, 0), 25.0);  // strictly below
  EXPECT_EQ(none.index, -1);
  EXPECT_EQ(none.squared_distance, std::numeric_limits<double>::infinity());
  EXPECT_EQ(tree.nearest(Eigen::Vector3d(5, 0, 0), 25.0001).index, 0);
  const NearestPointTree empty{Eigen::Matrix3Xd(3, 0)};
  EXPECT_EQ(empty.nearest(Eigen::Vector3d::Zero()).index, -1);
}

}  // namespace
