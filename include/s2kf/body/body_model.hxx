/// @file
/// The definitions of <s2kf/body/body_model.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/body/body_model.hpp>

namespace s2kf::body {

S2KF_INLINE BodyModel BodyModel::scaled(double new_height_mm) const {
  if (!(new_height_mm > 0) || !std::isfinite(new_height_mm))
    throw std::invalid_argument(
        "BodyModel::scaled: the height must be a positive number of millimetres, got " +
        std::to_string(new_height_mm));
  BodyModel result = *this;
  const double factor = new_height_mm / height_mm;
  result.height_mm = new_height_mm;
  for (auto& joint : result.joints) joint.translation *= factor;
  for (auto& marker : result.markers) marker.offset *= factor;
  return result;
}

S2KF_INLINE void BodyModel::validate() const {
  if (!(height_mm > 0) || !std::isfinite(height_mm))
    throw std::invalid_argument("BodyModel: height_mm must be positive and finite");
  for (int j = 0; j < joint_count(); ++j) {
    const Joint& joint = joints[j];
    if (joint.parent_frame < 0 || joint.parent_frame > j)
      throw std::invalid_argument("BodyModel: joint " + joint.name + " has parent frame " +
                                  std::to_string(joint.parent_frame) + ", which is not an earlier frame");
    if (!joint.translation.allFinite() || !std::isfinite(joint.lower) || !std::isfinite(joint.upper))
      throw std::invalid_argument("BodyModel: joint " + joint.name + " has a non-finite number");
    if (joint.lower > joint.upper)
      throw std::invalid_argument("BodyModel: joint " + joint.name + " has lower limit above upper limit");
  }
  for (const Marker& marker : markers) {
    if (marker.frame < 0 || marker.frame >= frame_count())
      throw std::invalid_argument("BodyModel: marker " + marker.name + " rides on frame " +
                                  std::to_string(marker.frame) + ", which does not exist");
    if (!marker.offset.allFinite())
      throw std::invalid_argument("BodyModel: marker " + marker.name + " has a non-finite offset");
  }
}

S2KF_INLINE BodyModel mmm_body_model(double height_mm) {
  // Build at 1000 mm, where the table numbers live, then scale once.
  BodyModel model;
  model.height_mm = 1000;
  struct Group {
    std::string name;
    Eigen::Vector3d centre;
    int end_frame;
  };
  std::vector<Group> groups{{"root", Eigen::Vector3d::Zero(), 0}};
  auto find_group = [&groups](const std::string& name) -> const Group& {
    for (const Group& group : groups)
      if (group.name == name) return group;
    throw std::logic_error("mmm_body_model: unknown group " + name);
  };
  for (int j = 0; j < kJointCount; ++j) {
    const mmm::JointRow& row = mmm::kJointTable[j];
    Joint joint;
    joint.name = row.name;
    joint.group = joint.name.substr(0, joint.name.size() - 1);
    joint.axis = row.axis == 'x' ? Axis::x : row.axis == 'y' ? Axis::y : Axis::z;
    joint.lower = row.lower;
    joint.upper = row.upper;
    if (row.parent_group != nullptr) {
      const Group& parent = find_group(row.parent_group);
      const Eigen::Vector3d centre(row.centre_x, row.centre_y, row.centre_z);
      joint.parent_frame = parent.end_frame;
      joint.translation = centre - parent.centre;
      groups.push_back({joint.group, centre, j + 1});
    } else {
      joint.parent_frame = j;  // the previous DoF of the same group
      groups.back().end_frame = j + 1;
    }
    model.joints.push_back(joint);
  }
  for (const mmm::MarkerRow& row : mmm::kMarkerTable) {
    Marker marker;
    marker.name = row.name;
    // A joint name (LEx) means "after that DoF"; its centre is its group's centre.
    const std::string rides_on = row.rides_on;
    const int joint = model.joint_index(rides_on);
    const Group& group = find_group(joint >= 0 ? model.joints[joint].group : rides_on);
    marker.frame = joint >= 0 ? joint + 1 : group.end_frame;
    marker.offset = Eigen::Vector3d(row.x, row.y, row.z) - group.centre;
    model.markers.push_back(marker);
  }
  return model.scaled(height_mm);
}

}  // namespace s2kf::body
