/// @file
/// Marker sets as data: which recording label rides on which model frame, where (offset in that
/// frame, or "like" a marker of the base model), how much to trust it; applying a set to a body
/// model, with the errors and observability warnings a user needs. See docs/real-data.md.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/label_text.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::body {

/// One physical marker of a lab's set.
struct MarkerSetEntry {
  std::string label;                 ///< the recording label (without subject prefix), e.g. "LFWT"
  std::vector<std::string> aliases;  ///< other labels labs use for the same marker, e.g. "LFRA" for "LFRM"
  /// Frame it rides on: "root", a group ("LS" = after the group's last DoF) or a joint ("LEx").
  /// Empty with `like`: the frame of the named base-model marker.
  std::string frame;
  /// When set: start from the position of this marker of the base model (e.g. "LASI"), expressed
  /// in `frame` at the zero pose, and add `offset`.
  std::optional<std::string> like;
  /// mm at the set's reference height, in `frame` (added to the `like` position when given).
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  std::optional<double>
      noise_mm;         ///< per-coordinate SD against the model, when it differs from the tracker's
  double weight = 1.0;  ///< relative weight in the subject calibration's least squares
};

/// A lab's marker set, or a calibrated subject (then `height_mm` and `segment_scale` are filled).
struct MarkerSet {
  std::string name;
  std::string description;
  double reference_height_mm = 1000.0;  ///< the height the offsets are given for
  std::optional<double> height_mm;      ///< a calibrated subject's body height
  /// Per segment ("root" or a joint group): factor on the lengths of the bones leaving it (the
  /// translations of the child joints), on top of the height scaling.
  std::map<std::string, double> segment_scale;
  /// Per joint ("LKx"): [lower, upper] in radians, replacing the model's range. For subjects or
  /// motions past the model's ranges (the MMM knee stops at 130 degrees of flexion; a deep squat or
  /// kneeling goes further), since the bounded joints never leave the range they are given.
  std::map<std::string, std::array<double, 2>> joint_limits;
  std::vector<MarkerSetEntry> entries;

  std::vector<std::string> labels() const {
    std::vector<std::string> result;
    for (const MarkerSetEntry& entry : entries) result.push_back(entry.label);
    return result;
  }
};

/// The base model's own markers as a marker set (labels = marker names, each `like` itself): what a
/// recording labelled with the model's names (KIT's set, the simulator's) is tracked with when no
/// marker-set file is at hand.
inline MarkerSet model_marker_set(const BodyModel& base, std::string name = "model") {
  MarkerSet set;
  set.name = std::move(name);
  set.description = "the body model's own markers";
  set.reference_height_mm = base.height_mm;
  for (const Marker& marker : base.markers) {
    MarkerSetEntry entry;
    entry.label = marker.name;
    entry.like = marker.name;
    set.entries.push_back(entry);
  }
  return set;
}

/// The segment a frame belongs to: "root" for frame 0, else its joint's group.
inline std::string segment_of_frame(const BodyModel& model, int frame) {
  return frame == 0 ? std::string("root") : model.joints.at(static_cast<std::size_t>(frame - 1)).group;
}

/// The indices of the model's markers that ride on `segment` ("root", "LE", ...).
inline std::vector<int> markers_on_segment(const BodyModel& model, const std::string& segment) {
  std::vector<int> markers;
  for (int m = 0; m < model.marker_count(); ++m)
    if (segment_of_frame(model, model.markers[static_cast<std::size_t>(m)].frame) == segment)
      markers.push_back(m);
  return markers;
}

/// The name a marker-set file uses for a frame: the group name when the frame ends its group
/// (what `frame_index(group)` finds), else the joint name ("LEx").
inline std::string marker_set_frame_name(const BodyModel& model, int frame) {
  if (frame == 0) return "root";
  const std::string& group = model.joints.at(static_cast<std::size_t>(frame - 1)).group;
  return model.frame_index(group) == frame ? group : model.frame_name(frame);
}

/// Throws std::invalid_argument for a set that cannot be applied to `base`: no entries, an empty
/// label, a label (or alias) used twice (case-insensitive), an unknown frame, segment or `like`
/// marker, a non-finite offset, a noise that is not positive, a negative weight.
void validate_marker_set(const BodyModel& base, const MarkerSet& set);

/// The base model with its markers replaced by the set's, in the set's order. The set's offsets
/// are scaled by base.height_mm / reference_height_mm; `like` positions are read from the base
/// model's own markers (so `base` must carry them, e.g. mmm_body_model(height)). Segment scales
/// multiply the translations of the joints leaving each segment; joint limits replace the model's.
BodyModel apply_marker_set(const BodyModel& base, const MarkerSet& set);

/// What a user should know before tracking with `model` (a base model after apply_marker_set):
/// segments the base model observed that the set leaves with no marker, and segments with a single
/// marker, whose rotation about the line from the joint to that marker no marker constrains.
std::vector<std::string> marker_set_warnings(const BodyModel& base, const BodyModel& model);

}  // namespace s2kf::body

#if !defined(S2KF_COMPILED)
#include <s2kf/body/marker_set.hxx>
#endif
