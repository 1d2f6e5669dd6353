/// @file
/// Checking and repairing which segment each marker of an inferred marker set rides on, from the
/// recording's own distances (rigid_clusters.hpp): markers on one segment keep their mutual
/// distances, markers on two segments that turn against each other do not. A marker whose distances
/// to its segment's other markers vary by centimetres while those to another segment's markers stay
/// constant rides on that other segment: a thigh marker put on the hand that hung beside it in the
/// template frame, a wrist marker put on the thigh.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/markerset/rigid_clusters.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace s2kf::markerset {

struct SegmentRigidityOptions {
  /// A marker leaves its segment only where the median SD of its distances to the segment's other
  /// markers exceeds this: centimetres, beyond soft tissue (8 mm per marker on the simulated
  /// subjects, about 11 mm on a distance between two of them) ...
  double misfit_sd_mm = 20.0;
  /// ... and the median SD to the markers of another segment is below this fraction of it.
  double move_ratio = 0.5;
  /// For a marker alone on its segment, compared with the adjacent segments' markers: their joints
  /// turn between them and it, so only a marker on the wrong limb altogether exceeds this (a thigh
  /// marker put on the hand, 400 mm in a simulated cartwheel; a shank marker against the thigh and
  /// foot of a handstand, 21 mm).
  double alone_misfit_sd_mm = 40.0;
};

/// How rigidly one marker rides with the markers of its segment and of the best other segment.
struct MarkerRigidity {
  std::string segment;  ///< the segment it is assigned to
  /// Median over the segment's other markers of the SD of the distance to them (mm); NaN where the
  /// segment has no other marker seen with it often enough: nothing to check it against.
  double own_sd_mm = std::numeric_limits<double>::quiet_NaN();
  std::string best_other_segment;  ///< the other segment whose markers keep the steadiest distances
  double best_other_sd_mm = std::numeric_limits<double>::quiet_NaN();
};

/// The median SD (clusters.distance_sd) of the distances from `point` to the points `others`, NaN
/// where none was seen with it often enough.
double median_distance_sd(const RigidClusters& clusters, int point, const std::vector<int>& others);

/// The recording points of each segment, for markers `points[i]` assigned to frames `frame_of[i]`.
inline std::map<std::string, std::vector<int>> points_by_segment(const body::BodyModel& base,
                                                                 const std::vector<int>& points,
                                                                 const std::vector<int>& frame_of) {
  std::map<std::string, std::vector<int>> by_segment;
  for (std::size_t i = 0; i < points.size(); ++i)
    by_segment[body::segment_of_frame(base, frame_of[i])].push_back(points[i]);
  return by_segment;
}

/// The segments next to `segment` in the model's tree: its parent and its children.
inline std::vector<std::string> adjacent_segments(const body::BodyModel& base, const std::string& segment) {
  std::vector<std::string> adjacent;
  for (const body::Joint& joint : base.joints) {
    const std::string parent = body::segment_of_frame(base, joint.parent_frame);
    if (joint.group == segment && parent != segment) adjacent.push_back(parent);
    if (parent == segment && joint.group != segment) adjacent.push_back(joint.group);
  }
  return adjacent;
}

/// Per marker i (recording point points[i], assigned to frame frame_of[i] of `base`): how rigidly
/// it rides with its segment's other markers and with the best other segment's. A marker alone on
/// its segment is compared with the markers of the adjacent segments instead (a hand marker moves
/// against the forearm's by the wrist's turn only, a thigh marker on the hand by much more), and
/// its best other segment is sought beyond them.
std::vector<MarkerRigidity> marker_rigidity(const RigidClusters& clusters, const body::BodyModel& base,
                                            const std::vector<int>& points, const std::vector<int>& frame_of);

/// One marker moved by repair_segment_assignment.
struct SegmentMove {
  std::size_t marker = 0;  ///< index into `points`
  std::string from, to;    ///< segments
  double from_sd_mm = 0;   ///< median distance SD to the markers of `from` before the move
  double to_sd_mm = 0;     ///< ... and to those of `to`
};

/// Moves markers to the segment they ride on rigidly, the marker that fits its own segment worst
/// first (of a wrist and a thigh marker put together on the thigh, the wrist marker's distances
/// vary most), and the rigidity measured again after each move, since a move changes two
/// segments' members. A marker moves where its distances to its own segment's markers vary by
/// more than options.misfit_sd_mm, to the segment whose markers keep them below options.move_ratio
/// of that (one next to its own where one qualifies: a marker at the hip rides on the pelvis, not
/// on a trunk that did not bend in the recording), onto the frame most of that segment's markers
/// ride on. Not between two segments that are both steady with it (a marker at a joint the
/// recording hardly turns): there the difference is soft tissue, and only the template can tell.
/// Returns the moves in order.
std::vector<SegmentMove> repair_segment_assignment(const RigidClusters& clusters, const body::BodyModel& base,
                                                   const std::vector<int>& points, std::vector<int>& frame_of,
                                                   const SegmentRigidityOptions& options = {});

}  // namespace s2kf::markerset

#if !defined(S2KF_COMPILED)
#include <s2kf/markerset/segment_rigidity.hxx>
#endif
