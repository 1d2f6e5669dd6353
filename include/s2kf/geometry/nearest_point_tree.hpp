/// @file
/// Exact nearest-point search among a fixed set of 3-D points: a k-d tree. The marker-set
/// inference asks it for every marker of tens of thousands of trial placements of its template
/// points, where comparing with every point took nearly all of its time.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <limits>
#include <numeric>
#include <vector>

namespace s2kf::geometry {

class NearestPointTree {
 public:
  struct Hit {
    Eigen::Index index = -1;  ///< the point's column in the matrix the tree was built from; -1: none
    double squared_distance = std::numeric_limits<double>::infinity();
  };

  /// A balanced tree over the columns of `points` (which it copies): each node splits its range
  /// at the median of the coordinate along which the range spreads furthest, down to ranges of at
  /// most kLeafPoints points, which a search scans.
  explicit NearestPointTree(const Eigen::Matrix3Xd& points)
      : points_(3, points.cols()),
        original_(static_cast<std::size_t>(points.cols())),
        axis_(static_cast<std::size_t>(points.cols()), 0) {
    std::iota(original_.begin(), original_.end(), Eigen::Index{0});
    build(points, 0, points.cols());
    for (Eigen::Index k = 0; k < points.cols(); ++k)
      points_.col(k) = points.col(original_[static_cast<std::size_t>(k)]);
  }

  /// The point nearest `query` among those at a squared distance below `below_squared_distance`;
  /// of equally near points, the one with the lowest index (as a scan through the columns would
  /// find). Hit::index is -1 where no point is that near.
  Hit nearest(const Eigen::Vector3d& query,
              double below_squared_distance = std::numeric_limits<double>::infinity()) const {
    Hit best;
    best.squared_distance = below_squared_distance;
    search(query, 0, points_.cols(), best);
    if (best.index < 0) best.squared_distance = std::numeric_limits<double>::infinity();
    return best;
  }

  Eigen::Index size() const { return points_.cols(); }

 private:
  /// A range this small is scanned: cheaper than descending further (the tree's depth).
  static constexpr Eigen::Index kLeafPoints = 8;

  void build(const Eigen::Matrix3Xd& points, Eigen::Index begin, Eigen::Index end) {
    if (end - begin <= kLeafPoints) return;
    Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d high = -low;
    for (Eigen::Index k = begin; k < end; ++k) {
      low = low.cwiseMin(points.col(original_[static_cast<std::size_t>(k)]));
      high = high.cwiseMax(points.col(original_[static_cast<std::size_t>(k)]));
    }
    int axis = 0;
    (high - low).maxCoeff(&axis);
    const Eigen::Index middle = begin + (end - begin) / 2;
    std::nth_element(original_.begin() + begin, original_.begin() + middle, original_.begin() + end,
                     [&](Eigen::Index a, Eigen::Index b) { return points(axis, a) < points(axis, b); });
    axis_[static_cast<std::size_t>(middle)] = axis;
    build(points, begin, middle);
    build(points, middle + 1, end);
  }

  /// Takes point k (tree order) where it is nearer than the best, or as near with a lower index.
  void consider(const Eigen::Vector3d& query, Eigen::Index k, Hit& best) const {
    const Eigen::Index index = original_[static_cast<std::size_t>(k)];
    const double d2 = (points_.col(k) - query).squaredNorm();
    if (d2 < best.squared_distance || (d2 == best.squared_distance && best.index >= 0 && index < best.index))
      best = {index, d2};
  }

  void search(const Eigen::Vector3d& query, Eigen::Index begin, Eigen::Index end, Hit& best) const {
    if (end - begin <= kLeafPoints) {
      for (Eigen::Index k = begin; k < end; ++k) consider(query, k, best);
      return;
    }
    const Eigen::Index middle = begin + (end - begin) / 2;
    consider(query, middle, best);
    const int axis = axis_[static_cast<std::size_t>(middle)];
    const double gap = query(axis) - points_(axis, middle);
    // The near side first; the far side only where it may hold a point as near as the best
    // (equally near, too: the lowest index wins a tie).
    const bool left_first = gap < 0;
    search(query, left_first ? begin : middle + 1, left_first ? middle : end, best);
    if (gap * gap <= best.squared_distance)
      search(query, left_first ? middle + 1 : begin, left_first ? end : middle, best);
  }

  Eigen::Matrix3Xd points_;             ///< the points in tree order
  std::vector<Eigen::Index> original_;  ///< per tree position, the point's index as given
  std::vector<int> axis_;               ///< per tree position, the axis its node splits
};

}  // namespace s2kf::geometry
