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

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

S2KF_INLINE RigidClusters find_rigid_clusters(const MarkerSequence& recording, const std::vector<int>& points,
                                              const RigidClusterOptions& options) {
  const Eigen::Index n = recording.point_count(), frames = recording.frame_count();
  RigidClusters result;
  result.distance_sd.setConstant(n, n, std::numeric_limits<double>::quiet_NaN());
  result.mean_distance = result.distance_sd;
  result.cluster_of_point.assign(static_cast<std::size_t>(n), -1);
  const long used_frames = std::max<long>(1, std::min<long>(options.max_frames, static_cast<long>(frames)));
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, n), sum2 = sum, count = sum;
  for (long k = 0; k < used_frames; ++k) {
    const Eigen::Index f = static_cast<Eigen::Index>(k * frames / used_frames);
    const auto frame = recording.frame(f);
    for (int a : points)
      for (int b : points)
        if (a < b && recording.visible(a, f) && recording.visible(b, f)) {
          const double d = (frame.col(a) - frame.col(b)).norm();
          sum(a, b) += d, sum2(a, b) += d * d, count(a, b) += 1;
        }
  }
  for (int a : points)
    for (int b : points)
      if (a < b && count(a, b) >= static_cast<double>(options.min_common)) {
        const double mean = sum(a, b) / count(a, b);
        const double sd = std::sqrt(std::max(0.0, sum2(a, b) / count(a, b) - mean * mean));
        result.distance_sd(a, b) = result.distance_sd(b, a) = sd;
        result.mean_distance(a, b) = result.mean_distance(b, a) = mean;
      }
  std::vector<std::vector<int>> clusters;
  for (int p : points) clusters.push_back({p});
  const auto linkage = [&](const std::vector<int>& x, const std::vector<int>& y) {
    double total = 0;
    for (int a : x)
      for (int b : y) total += rigidity_ratio(result, a, b, options);
    return total / static_cast<double>(x.size() * y.size());
  };
  for (;;) {
    double best = 1.0;
    std::size_t best_i = 0, best_j = 0;
    for (std::size_t i = 0; i < clusters.size(); ++i)
      for (std::size_t j = i + 1; j < clusters.size(); ++j)
        if (const double l = linkage(clusters[i], clusters[j]); l < best) best = l, best_i = i, best_j = j;
    if (best >= 1.0) break;
    clusters[best_i].insert(clusters[best_i].end(), clusters[best_j].begin(), clusters[best_j].end());
    clusters.erase(clusters.begin() + static_cast<std::ptrdiff_t>(best_j));
  }
  std::stable_sort(clusters.begin(), clusters.end(),
                   [](const auto& x, const auto& y) { return x.size() > y.size(); });
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    std::sort(clusters[c].begin(), clusters[c].end());
    for (int p : clusters[c]) result.cluster_of_point[static_cast<std::size_t>(p)] = static_cast<int>(c);
  }
  result.clusters = std::move(clusters);
  return result;
}

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::markerset
