/// @file
/// The column names of a pose table (CSV): what the tracker and the simulator write per frame and
/// what `s2kf model --pose` reads.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/pose.hpp>

#include <string>
#include <vector>

namespace s2kf::body {

/// The pose columns of `model`'s CSV (pose_column_names with its joint names).
inline std::vector<std::string> pose_column_names(const BodyModel& model) {
  return pose_column_names(model.joint_names());
}

/// The pose columns of the 40-joint MMM-style model.
inline std::vector<std::string> pose_column_names() {
  std::vector<std::string> joints;
  for (const mmm::JointRow& row : mmm::kJointTable) joints.emplace_back(row.name);
  return pose_column_names(joints);
}

}  // namespace s2kf::body
