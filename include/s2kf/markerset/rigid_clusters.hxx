/// @file
/// The definitions of <s2kf/markerset/rigid_clusters.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/markerset/rigid_clusters.hpp>

namespace s2kf::markerset {

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

}  // namespace s2kf::markerset
