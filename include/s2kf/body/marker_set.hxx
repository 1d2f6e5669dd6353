/// @file
/// The definitions of <s2kf/body/marker_set.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/body/marker_set.hpp>

namespace s2kf::body {

S2KF_INLINE void validate_marker_set(const BodyModel& base, const MarkerSet& set) {
  const std::string where = "marker set" + (set.name.empty() ? std::string() : " '" + set.name + "'");
  if (set.entries.empty()) throw std::invalid_argument(where + " has no markers");
  if (!(set.reference_height_mm > 0) || !std::isfinite(set.reference_height_mm))
    throw std::invalid_argument(where + ": reference_height_mm must be a positive number");
  if (set.height_mm && (!(*set.height_mm > 0) || !std::isfinite(*set.height_mm)))
    throw std::invalid_argument(where + ": height_mm must be a positive number");
  std::map<std::string, std::string> seen;  // upper-case label -> the entry that uses it
  for (const MarkerSetEntry& entry : set.entries) {
    if (entry.label.empty()) throw std::invalid_argument(where + ": a marker has an empty label");
    std::vector<std::string> names{entry.label};
    names.insert(names.end(), entry.aliases.begin(), entry.aliases.end());
    for (const std::string& name : names) {
      const auto [it, inserted] = seen.emplace(upper_case(name), entry.label);
      if (!inserted)
        throw std::invalid_argument(where + ": the label " + name + " is mapped twice (markers " +
                                    it->second + " and " + entry.label + ")");
    }
    if (entry.frame.empty() && !entry.like)
      throw std::invalid_argument(where + ": marker " + entry.label + " needs a frame or a \"like\" marker");
    if (!entry.frame.empty() && base.frame_index(entry.frame) < 0)
      throw std::invalid_argument(where + ": marker " + entry.label + " rides on the unknown frame '" +
                                  entry.frame +
                                  "' (use root, a joint group such as LS, or a joint such as LEx)");
    if (entry.like && base.marker_index(*entry.like) < 0)
      throw std::invalid_argument(where + ": marker " + entry.label + " is \"like\" " + *entry.like +
                                  ", which is not a marker of the base model");
    if (!entry.offset.allFinite())
      throw std::invalid_argument(where + ": marker " + entry.label + " has a non-finite offset");
    if (entry.noise_mm && (!(*entry.noise_mm > 0) || !std::isfinite(*entry.noise_mm)))
      throw std::invalid_argument(where + ": marker " + entry.label +
                                  " has a noise that is not a positive number");
    if (!(entry.weight >= 0) || !std::isfinite(entry.weight))
      throw std::invalid_argument(where + ": marker " + entry.label + " has a negative or non-finite weight");
  }
  for (const auto& [name, range] : set.joint_limits) {
    if (base.joint_index(name) < 0)
      throw std::invalid_argument(where + ": joint_limits names the unknown joint '" + name + "'");
    if (!std::isfinite(range[0]) || !std::isfinite(range[1]) || !(range[0] < range[1]) ||
        range[1] - range[0] > 2 * kPi)
      throw std::invalid_argument(where + ": the limits of joint " + name +
                                  " must be finite radians with lower < upper, at most 2 pi apart");
  }
  for (const auto& [segment, factor] : set.segment_scale) {
    bool known = segment == "root";
    for (const Joint& joint : base.joints) known = known || joint.group == segment;
    if (!known)
      throw std::invalid_argument(where + ": segment_scale names the unknown segment '" + segment + "'");
    if (!(factor > 0.5 && factor < 2.0))
      throw std::invalid_argument(where + ": the scale of segment " + segment +
                                  " must lie between 0.5 and 2");
  }
}

S2KF_INLINE BodyModel apply_marker_set(const BodyModel& base, const MarkerSet& set) {
  base.validate();
  validate_marker_set(base, set);
  const double factor = base.height_mm / set.reference_height_mm;
  const FrameTransforms zero = joint_frames(base, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(),
                                            Eigen::VectorXd::Zero(base.joint_count()));
  BodyModel model = base;
  model.markers.clear();
  for (const MarkerSetEntry& entry : set.entries) {
    Marker marker;
    marker.name = entry.label;
    Eigen::Vector3d offset = entry.offset * factor;
    if (entry.like) {
      const Marker& reference = base.markers[static_cast<std::size_t>(base.marker_index(*entry.like))];
      marker.frame = entry.frame.empty() ? reference.frame : base.frame_index(entry.frame);
      const Eigen::Vector3d world =
          zero.origins[static_cast<std::size_t>(reference.frame)] +
          zero.rotations[static_cast<std::size_t>(reference.frame)] * reference.offset;
      offset += zero.rotations[static_cast<std::size_t>(marker.frame)].transpose() *
                (world - zero.origins[static_cast<std::size_t>(marker.frame)]);
    } else {
      marker.frame = base.frame_index(entry.frame);
    }
    marker.offset = offset;
    model.markers.push_back(marker);
  }
  for (Joint& joint : model.joints) {
    const auto found = set.segment_scale.find(segment_of_frame(base, joint.parent_frame));
    if (found != set.segment_scale.end()) joint.translation *= found->second;
    if (const auto limits = set.joint_limits.find(joint.name); limits != set.joint_limits.end()) {
      joint.lower = limits->second[0];
      joint.upper = limits->second[1];
    }
  }
  model.validate();
  return model;
}

S2KF_INLINE std::vector<std::string> marker_set_warnings(const BodyModel& base, const BodyModel& model) {
  std::map<std::string, int> base_count, count;
  for (const Marker& marker : base.markers) ++base_count[segment_of_frame(base, marker.frame)];
  for (const Marker& marker : model.markers) ++count[segment_of_frame(model, marker.frame)];
  std::vector<std::string> warnings;
  std::vector<std::string> segments{"root"};
  for (const Joint& joint : model.joints)
    if (std::find(segments.begin(), segments.end(), joint.group) == segments.end())
      segments.push_back(joint.group);
  for (const std::string& segment : segments) {
    const int n = count.count(segment) ? count[segment] : 0;
    if (n == 0 && base_count.count(segment))
      warnings.push_back(segment +
                         " has no marker: its joints follow only their neighbours and the motion prior");
    else if (n == 1)
      warnings.push_back(segment +
                         " has 1 marker: its rotation is not observable about the line from its joint "
                         "centre to that marker");
  }
  return warnings;
}

}  // namespace s2kf::body
