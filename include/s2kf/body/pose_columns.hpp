/// @file
/// The column names of a pose table (CSV): what the tracker and the simulator write per frame and
/// what `s2kf model --pose` reads.
#pragma once

#include <s2kf/body/body_model.hpp>

#include <string>
#include <vector>

namespace s2kf::body {

/// frame, time (s), root_x, root_y, root_z (mm), root_roll, root_pitch, root_yaw (rad, R = Rz Ry Rx),
/// then the joint angles (rad) under the model's joint names in state order.
inline std::vector<std::string> pose_column_names(const BodyModel& model) {
  std::vector<std::string> names{"frame",  "time",      "root_x",     "root_y",
                                 "root_z", "root_roll", "root_pitch", "root_yaw"};
  for (const Joint& joint : model.joints) names.push_back(joint.name);
  return names;
}

/// The pose columns of the 40-joint MMM-style model.
inline std::vector<std::string> pose_column_names() {
  std::vector<std::string> names{"frame",  "time",      "root_x",     "root_y",
                                 "root_z", "root_roll", "root_pitch", "root_yaw"};
  for (const mmm::JointRow& row : mmm::kJointTable) names.emplace_back(row.name);
  return names;
}

}  // namespace s2kf::body
