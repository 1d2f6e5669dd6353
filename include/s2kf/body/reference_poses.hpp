/// @file
/// The postures people are asked to hold in a static trial, as joint angles of the body model:
/// the model's zero pose (upright, arms hanging), the T-pose (arms straight out to the sides) and
/// the A-pose (arms 45 degrees down from the T). Everything but the shoulders' abduction is 0.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/core/constants.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::body {

/// The names reference_pose knows, in the order a posture found from the data is chosen among.
inline std::vector<std::string> reference_pose_names() { return {"zero", "t-pose", "a-pose"}; }

/// Whether `name` is one of reference_pose_names() (not, say, a pose file).
inline bool is_reference_pose(const std::string& name) {
  const std::vector<std::string> names = reference_pose_names();
  return std::find(names.begin(), names.end(), name) != names.end();
}

/// The joint angles (rad) of a named reference pose; std::invalid_argument for another name.
inline Eigen::VectorXd reference_pose(const BodyModel& model, const std::string& name) {
  double abduction_deg = 0;  // of each upper arm, away from the trunk in the frontal plane
  if (name == "t-pose")
    abduction_deg = 90;
  else if (name == "a-pose")
    abduction_deg = 45;
  else if (name != "zero")
    throw std::invalid_argument("unknown reference pose '" + name + "' (zero, t-pose or a-pose)");
  Eigen::VectorXd joints = Eigen::VectorXd::Zero(model.joint_count());
  // LSy and RSy turn the upper arms about the forward axis, the left one positive (the table's limits).
  const int left = model.joint_index("LSy"), right = model.joint_index("RSy");
  if (abduction_deg > 0 && (left < 0 || right < 0))
    throw std::invalid_argument("the body model has no shoulder abduction (LSy, RSy) for the " + name);
  if (left >= 0) joints(left) = abduction_deg / kDegreesPerRadian;
  if (right >= 0) joints(right) = -abduction_deg / kDegreesPerRadian;
  return joints;
}

}  // namespace s2kf::body
