/// @file
/// Rigid clusters of an unlabelled recording: groups of markers whose mutual distances stay
/// (nearly) constant over the recording, as markers on one body segment do. Soft tissue makes them
/// only nearly constant, so a pair counts as rigid when the standard deviation of its distance is
/// small against a floor plus a fraction of the distance itself.
#pragma once

#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/marker_sequence.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace s2kf::markerset {

struct RigidClusterOptions {
  /// A pair is rigid when its distance's SD stays below floor_mm + fraction * mean distance: sensor
  /// noise and a few mm of skin motion pass, a joint that turns 20 degrees (a marker 300 mm away
  /// moves about 100 mm) does not. The 8 mm soft-tissue artefact of the simulated subjects splits
  /// some segments into several clusters, which the inference allows.
  double floor_mm = 6.0;
  double fraction = 0.01;
  long max_frames = 600;  ///< frames used at most, spread evenly over the recording
  long min_common = 10;   ///< frames in which both markers of a pair must be seen
};

struct RigidClusters {
  /// Point indices of each cluster, the largest cluster first.
  std::vector<std::vector<int>> clusters;
  /// Per pair of points: SD and mean of their distance (mm); NaN where seen together too rarely.
  Eigen::MatrixXd distance_sd, mean_distance;
  /// Per point: its cluster (index into `clusters`), -1 for a point never seen.
  std::vector<int> cluster_of_point;
};

/// The ratio of a pair's distance SD to its rigidity threshold (below 1: rigid), infinity when the
/// pair was not seen together often enough.
inline double rigidity_ratio(const RigidClusters& c, int a, int b, const RigidClusterOptions& options) {
  const double sd = c.distance_sd(a, b);
  if (!std::isfinite(sd)) return std::numeric_limits<double>::infinity();
  return sd / (options.floor_mm + options.fraction * c.mean_distance(a, b));
}

/// Average-linkage agglomeration of the points of `recording` (only those in `points`, e.g. the
/// labelled ones): two clusters merge while the mean rigidity ratio over their pairs is below 1.
RigidClusters find_rigid_clusters(const MarkerSequence& recording, const std::vector<int>& points,
                                  const RigidClusterOptions& options = {});

}  // namespace s2kf::markerset

#if !defined(S2KF_COMPILED)
#include <s2kf/markerset/rigid_clusters.hxx>
#endif
