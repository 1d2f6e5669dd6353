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
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/io/marker_sequence.hpp>
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

}  // namespace s2kf::track

#if !defined(S2KF_COMPILED)
#include <s2kf/track/segment_observation.hxx>
#endif
