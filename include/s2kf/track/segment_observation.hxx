/// @file
/// The definitions of <s2kf/track/segment_observation.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/track/segment_observation.hpp>

namespace s2kf::track {

S2KF_INLINE SegmentObservation observe_segments(const body::BodyModel& model,
                                                const body::MarkerMapping& mapping,
                                                std::vector<int>* point_segment) {
  SegmentObservation result;
  result.segments.push_back("root");
  for (const body::Joint& joint : model.joints)
    if (result.segment_index(joint.group) < 0) result.segments.push_back(joint.group);
  const std::size_t n = result.segments.size();
  result.markers.assign(n, 0);
  result.informed.assign(n, false);
  result.frames_without_marker.assign(n, 0);
  // The frame a segment hangs from: the parent frame of its group's first joint.
  const auto parent_frame_of = [&model](const std::string& group) {
    for (const body::Joint& joint : model.joints)
      if (joint.group == group) return joint.parent_frame;
    return 0;
  };
  int largest_point = -1;
  for (int p : mapping.point_of_marker) largest_point = std::max(largest_point, p);
  if (point_segment) point_segment->assign(static_cast<std::size_t>(largest_point + 1), -1);
  for (int m = 0; m < model.marker_count(); ++m) {
    const int point = mapping.point_of_marker[static_cast<std::size_t>(m)];
    if (point < 0) continue;
    int frame = model.markers[static_cast<std::size_t>(m)].frame;
    const int own = result.segment_index(body::segment_of_frame(model, frame));
    ++result.markers[static_cast<std::size_t>(own)];
    if (point_segment) (*point_segment)[static_cast<std::size_t>(point)] = own;
    while (true) {
      const std::string segment = body::segment_of_frame(model, frame);
      result.informed[static_cast<std::size_t>(result.segment_index(segment))] = true;
      if (frame == 0) break;
      frame = parent_frame_of(segment);
    }
  }
  for (int j = 0; j < model.joint_count(); ++j)
    if (!result.informed[static_cast<std::size_t>(result.segment_index(model.joints[j].group))])
      result.unobserved_joints.push_back(j);
  return result;
}

S2KF_INLINE Eigen::VectorXd segment_uncertainty_deg(const body::BodyModel& model,
                                                    const SegmentObservation& segments,
                                                    const Eigen::VectorXd& angles,
                                                    const Eigen::MatrixXd& covariance) {
  Eigen::VectorXd result = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(segments.segments.size()),
                                                     std::numeric_limits<double>::quiet_NaN());
  const Eigen::Index states = kFirstJointState + model.joint_count();
  if (covariance.rows() != states || covariance.cols() != states || angles.size() != model.joint_count() ||
      !angles.allFinite())
    return result;
  const Eigen::VectorXd parameters = body::BoundedJoints(model).parameters(angles);
  const Eigen::Matrix3d orientation = covariance.block<3, 3>(3, 3);
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(orientation).eigenvalues().maxCoeff();
  result(0) = std::sqrt(std::max(0.0, largest)) * kDegreesPerRadian;
  for (int j = 0; j < model.joint_count(); ++j) {
    const body::Joint& joint = model.joints[static_cast<std::size_t>(j)];
    const Eigen::Index k = kFirstJointState + j;
    const double sd = bounded_angle_sd(0.5 * (joint.upper - joint.lower), parameters(j), covariance(k, k)) *
                      kDegreesPerRadian;
    const auto s = static_cast<Eigen::Index>(segments.segment_index(joint.group));
    result(s) = std::isnan(result(s)) ? sd : std::max(result(s), sd);
  }
  return result;
}

}  // namespace s2kf::track
