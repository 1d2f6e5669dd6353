/// @file
/// Whether a marker set inferred from a recording describes a whole body: how far its markers
/// spread against the body's height, and the regions (trunk, head, arms, legs) they ride on. A face
/// or an object does not describe a body the tracker can follow, and the program says so.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/io/marker_sequence.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

#include <map>
#include <string>
#include <vector>

namespace s2kf::markerset {

/// The region of a segment of the MMM model: "trunk" (root, BP, BT), "head" (BLN, BUN), "left arm"
/// (LS, LE, LW), "right arm", "left leg" (LH, LK, LA), "right leg".
inline std::string body_region(const body::BodyModel& base, const std::string& segment) {
  const auto trunk = [](const std::string& s) { return s == "root" || s == "BP" || s == "BT"; };
  if (trunk(segment)) return "trunk";
  std::string top = segment;
  for (int guard = 0; guard < base.joint_count(); ++guard) {
    const int frame = base.frame_index(top);
    if (frame <= 0) break;
    int first = -1;  // the group's first DoF, whose parent frame is the parent segment's
    for (int j = 0; j < base.joint_count() && first < 0; ++j)
      if (base.joints[static_cast<std::size_t>(j)].group == top) first = j;
    const std::string parent =
        body::segment_of_frame(base, base.joints[static_cast<std::size_t>(first)].parent_frame);
    if (trunk(parent)) break;
    top = parent;
  }
  static const std::map<std::string, std::string> names{
      {"LS", "left arm"}, {"RS", "right arm"}, {"LH", "left leg"}, {"RH", "right leg"}, {"BLN", "head"}};
  const auto found = names.find(top);
  return found == names.end() ? top : found->second;
}

/// The regions that carry at least two of the markers of `model` (a set applied to the MMM model),
/// in the order first met.
inline std::vector<std::string> covered_regions(const body::BodyModel& model) {
  std::map<std::string, int> count;
  std::vector<std::string> order, covered;
  for (const body::Marker& marker : model.markers) {
    const std::string region = body_region(model, body::segment_of_frame(model, marker.frame));
    if (count[region]++ == 0) order.push_back(region);
  }
  for (const std::string& region : order)
    if (count[region] >= 2) covered.push_back(region);
  return covered;
}

/// The markers' extent: the median, over up to 200 frames spread over the recording, of the
/// diagonal of the box around the labelled points seen in the frame (mm).
inline double marker_extent_mm(const MarkerSequence& recording) {
  std::vector<double> diagonals;
  const Eigen::Index frames = recording.frame_count(), step = std::max<Eigen::Index>(1, frames / 200);
  for (Eigen::Index f = 0; f < frames; f += step) {
    Eigen::Vector3d low = Eigen::Vector3d::Constant(INFINITY), high = -low;
    int seen = 0;
    for (Eigen::Index p = 0; p < recording.point_count(); ++p)
      if (recording.visible(p, f) && !recording.labels[static_cast<std::size_t>(p)].empty()) {
        low = low.cwiseMin(recording.frame(f).col(p)), high = high.cwiseMax(recording.frame(f).col(p));
        ++seen;
      }
    if (seen >= 2) diagonals.push_back((high - low).norm());
  }
  if (diagonals.empty()) return 0;
  std::nth_element(diagonals.begin(), diagonals.begin() + static_cast<long>(diagonals.size() / 2),
                   diagonals.end());
  return diagonals[diagonals.size() / 2];
}

/// A sentence saying why `model`'s markers do not describe a whole body, or empty when they do:
/// they span less than 35 % of the body's height `height_mm` (`extent_mm`, marker_extent_mm: a
/// face, a hand; a lower-body or upper-body set spans over half), or they ride on fewer than three
/// regions with two markers each.
inline std::string whole_body_problem(const body::BodyModel& model, double extent_mm = NAN,
                                      double height_mm = NAN) {
  if (extent_mm < 0.35 * height_mm)
    return "the recording does not look like a whole body: its markers span " +
           std::to_string(std::lround(extent_mm)) + " mm, " +
           std::to_string(std::lround(100 * extent_mm / height_mm)) + " % of the " +
           std::to_string(std::lround(height_mm)) +
           " mm body fitted to them (a whole body's markers span at least 35 %)";
  const std::vector<std::string> covered = covered_regions(model);
  if (covered.size() >= 3) return {};
  std::string list;
  for (std::size_t k = 0; k < covered.size(); ++k)
    list += (k == 0 ? "" : k + 1 == covered.size() ? " and " : ", ") + covered[k];
  return "the recording does not look like a whole body: its markers ride on " +
         (covered.empty() ? std::string("no region") : "only the " + list) +
         " (a body needs at least three of trunk, head, arms and legs with two markers each)";
}

}  // namespace s2kf::markerset
