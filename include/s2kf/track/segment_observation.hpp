/// @file
/// What a recording tells about each body segment: which segments carry markers of the set, which
/// joints no marker informs at all (a lower-body recording's spine and arms: written as not
/// observed, NaN, never invented), how many frames each segment went without a visible marker, and
/// each segment's per-frame confidence from the filter's covariance.
///
/// Segments are the root (the pelvis) and the joint groups ("LE" = the forearm the elbow moves).
/// A joint is informed when a marker rides on its segment or on a segment beyond it in the chain
/// (the lower back BP carries no marker, but the trunk above it does).
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/bounded_joints.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/track/state_chart.hpp>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace s2kf::track {

struct SegmentObservation {
  std::vector<std::string> segments;        ///< "root", then each joint group in model order
  std::vector<int> markers;                 ///< per segment: markers of the set found in the recording
  std::vector<bool> informed;               ///< per segment: a found marker rides on it or beyond it
  std::vector<int> unobserved_joints;       ///< joints of segments that are not informed (written as NaN)
  std::vector<long> frames_without_marker;  ///< per segment: frames in which none of its markers was seen
  long frames = 0;                          ///< frames counted

  int segment_index(const std::string& name) const {
    const auto found = std::find(segments.begin(), segments.end(), name);
    return found == segments.end() ? -1 : static_cast<int>(found - segments.begin());
  }

  /// The segments no marker informs, by name.
  std::vector<std::string> unobserved_segments() const {
    std::vector<std::string> names;
    for (std::size_t s = 0; s < segments.size(); ++s)
      if (!informed[s]) names.push_back(segments[s]);
    return names;
  }

  /// Counts, per segment with markers, whether this frame shows none of them (visible: per
  /// recording point; point_segment: the segment of each recording point, -1 where unmapped).
  void count_frame(const FrameVisibility& visible, const std::vector<int>& point_segment) {
    std::vector<bool> seen(segments.size(), false);
    for (std::size_t p = 0; p < point_segment.size(); ++p)
      if (point_segment[p] >= 0 && static_cast<Eigen::Index>(p) < visible.size() &&
          visible(static_cast<Eigen::Index>(p)))
        seen[static_cast<std::size_t>(point_segment[p])] = true;
    for (std::size_t s = 0; s < segments.size(); ++s)
      if (markers[s] > 0 && !seen[s]) ++frames_without_marker[s];
    ++frames;
  }
};

/// The segments of `model` (a set applied to the base model) and what `mapping` lets the recording
/// observe of them. `point_segment` (optional) receives the segment of every recording point.
SegmentObservation observe_segments(const body::BodyModel& model, const body::MarkerMapping& mapping,
                                    std::vector<int>* point_segment = nullptr);

/// Standard deviation of theta = middle + half sin(Theta) for Theta ~ N(mean, variance), exactly:
/// E[sin] = sin(m) e^(-v/2), E[sin^2] = (1 - cos(2m) e^(-2v)) / 2. Unlike the linearisation
/// (half |cos m| sqrt(v)) it does not fall to zero at a limit, and it tends to half / sqrt(2) for
/// a parameter nothing constrains.
inline double bounded_angle_sd(double half_range, double mean, double variance) {
  const double e_sin = std::sin(mean) * std::exp(-0.5 * variance);
  const double e_sin2 = 0.5 * (1.0 - std::cos(2.0 * mean) * std::exp(-2.0 * variance));
  return half_range * std::sqrt(std::max(0.0, e_sin2 - e_sin * e_sin));
}

/// Per segment, how uncertain the filter is about it this frame, from the posterior covariance of
/// the state [root position, orientation error, Theta] at the joint angles `angles` (the tracker keeps
/// Theta on the principal branch, so Theta follows from the angle): for the root, the
/// largest standard deviation of its orientation (deg); for a joint group, the largest standard
/// deviation of its angles (deg, bounded_angle_sd). NaN where the covariance is not given.
Eigen::VectorXd segment_uncertainty_deg(const body::BodyModel& model, const SegmentObservation& segments,
                                        const Eigen::VectorXd& angles, const Eigen::MatrixXd& covariance);

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

S2KF_INLINE SegmentObservation observe_segments(const body::BodyModel& model, const body::MarkerMapping& mapping,
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

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::track
