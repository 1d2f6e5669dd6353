/// @file
/// The definitions of <s2kf/markerset/segment_rigidity.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/markerset/segment_rigidity.hpp>

namespace s2kf::markerset {

S2KF_INLINE double median_distance_sd(const RigidClusters& clusters, int point,
                                      const std::vector<int>& others) {
  std::vector<double> sd;
  for (int other : others)
    if (other != point && std::isfinite(clusters.distance_sd(point, other)))
      sd.push_back(clusters.distance_sd(point, other));
  if (sd.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto middle = sd.begin() + static_cast<std::ptrdiff_t>(sd.size() / 2);
  std::nth_element(sd.begin(), middle, sd.end());
  if (sd.size() % 2 == 1) return *middle;
  return 0.5 * (*middle + *std::max_element(sd.begin(), middle));
}

S2KF_INLINE std::vector<MarkerRigidity> marker_rigidity(const RigidClusters& clusters,
                                                        const body::BodyModel& base,
                                                        const std::vector<int>& points,
                                                        const std::vector<int>& frame_of) {
  const auto by_segment = points_by_segment(base, points, frame_of);
  std::vector<MarkerRigidity> result(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    MarkerRigidity& r = result[i];
    r.segment = body::segment_of_frame(base, frame_of[i]);
    std::vector<std::string> own{r.segment};
    if (by_segment.at(r.segment).size() < 2) own = adjacent_segments(base, r.segment);
    std::vector<int> own_points;
    for (const std::string& segment : own)
      if (const auto found = by_segment.find(segment); found != by_segment.end())
        own_points.insert(own_points.end(), found->second.begin(), found->second.end());
    r.own_sd_mm = median_distance_sd(clusters, points[i], own_points);
    for (const auto& [segment, members] : by_segment) {
      if (segment == r.segment || std::find(own.begin(), own.end(), segment) != own.end()) continue;
      const double sd = median_distance_sd(clusters, points[i], members);
      if (std::isfinite(sd) && !(sd >= r.best_other_sd_mm))
        r.best_other_sd_mm = sd, r.best_other_segment = segment;
    }
  }
  return result;
}

S2KF_INLINE std::vector<SegmentMove> repair_segment_assignment(const RigidClusters& clusters,
                                                               const body::BodyModel& base,
                                                               const std::vector<int>& points,
                                                               std::vector<int>& frame_of,
                                                               const SegmentRigidityOptions& options) {
  std::vector<SegmentMove> moves;
  for (std::size_t step = 0; step < points.size(); ++step) {
    const std::vector<MarkerRigidity> rigidity = marker_rigidity(clusters, base, points, frame_of);
    const auto by_segment = points_by_segment(base, points, frame_of);
    std::size_t worst = points.size();
    std::string worst_target;
    double worst_own = 0, worst_target_sd = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const MarkerRigidity& r = rigidity[i];
      if (!(r.own_sd_mm > worst_own)) continue;
      const bool alone = by_segment.at(r.segment).size() < 2;
      const bool misfit = r.own_sd_mm > (alone ? options.alone_misfit_sd_mm : options.misfit_sd_mm) &&
                          r.best_other_sd_mm < options.move_ratio * r.own_sd_mm;
      if (!misfit) continue;
      std::string target = r.best_other_segment;
      double target_sd = r.best_other_sd_mm;
      double adjacent_sd = options.move_ratio * r.own_sd_mm;  // an adjacent segment, where one qualifies
      if (!alone)
        for (const std::string& segment : adjacent_segments(base, r.segment))
          if (const auto found = by_segment.find(segment); found != by_segment.end()) {
            const double sd = median_distance_sd(clusters, points[i], found->second);
            if (sd < adjacent_sd) adjacent_sd = sd, target = segment, target_sd = sd;
          }
      if (target.empty()) continue;
      worst = i, worst_own = r.own_sd_mm, worst_target = target, worst_target_sd = target_sd;
    }
    if (worst == points.size()) break;
    std::map<int, int> frame_votes;
    for (std::size_t j = 0; j < points.size(); ++j)
      if (j != worst && body::segment_of_frame(base, frame_of[j]) == worst_target) ++frame_votes[frame_of[j]];
    const auto target = std::max_element(frame_votes.begin(), frame_votes.end(),
                                         [](const auto& x, const auto& y) { return x.second < y.second; });
    moves.push_back({worst, rigidity[worst].segment, worst_target, worst_own, worst_target_sd});
    frame_of[worst] = target->first;
  }
  return moves;
}

}  // namespace s2kf::markerset
