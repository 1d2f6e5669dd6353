/// @file
/// A simulated subject: a person who differs from the body model the tracker uses (height,
/// segment lengths, where each marker was stuck, skin that slides) and a camera that adds noise.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/sim/random.hpp>
#include <s2kf/sim/soft_tissue.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::sim {

/// How the subject differs from the model. The defaults resemble a careful Vicon session: markers
/// stuck by a trained person (about 1.3 cm mean displacement), centimetre soft-tissue motion,
/// sub-millimetre camera noise, segment lengths a few per cent off the anthropometric table.
struct SubjectOptions {
  double height_mm = 1750.0;
  /// Relative SD of each segment's length factor (clamped to [0.85, 1.15]); 0.03 = 3 %.
  double segment_scale_sd = 0.03;
  /// SD per coordinate of each marker's fixed placement offset; the mean 3D displacement is
  /// sqrt(8/pi) = 1.6 times this, 8 mm -> 1.3 cm.
  double placement_sd_mm = 8.0;
  /// Scale of the soft-tissue artefact (see draw_soft_tissue); 8 mm gives about 8 mm RMS in 3D
  /// over the bundled motions, with peaks near 2 cm.
  double soft_tissue_mm = 8.0;
  /// SD per coordinate and frame of the sensor noise.
  double noise_sd_mm = 0.7;
};

/// Throws std::invalid_argument unless every option is finite, non-negative and the height positive.
inline void validate(const SubjectOptions& options) {
  if (!(options.height_mm > 0.0) || !std::isfinite(options.height_mm))
    throw std::invalid_argument("the subject height must be a positive number of mm");
  const auto check = [](double value, const char* what) {
    if (!(value >= 0.0) || !std::isfinite(value))
      throw std::invalid_argument(std::string("the ") + what + " must be a finite number >= 0");
  };
  check(options.segment_scale_sd, "segment scale SD");
  check(options.placement_sd_mm, "marker placement SD");
  check(options.soft_tissue_mm, "soft-tissue scale");
  check(options.noise_sd_mm, "sensor noise SD");
}

/// The drawn subject. `model` is the subject's own skeleton with the markers where they were
/// placed; soft tissue moves them further at every instant (model_at).
struct Subject {
  double height_mm = 1750.0;
  body::BodyModel model;
  std::vector<std::string> joint_names, marker_names;
  Eigen::VectorXd lower, upper;         ///< joint limits, rad
  std::vector<std::string> segments;    ///< segment names: "root" and the joint groups
  Eigen::VectorXd segment_scale;        ///< length factor per segment
  std::vector<int> marker_segment;      ///< index into segments, per marker
  Eigen::Matrix3Xd placement;           ///< mm, per marker, in the frame it rides on
  std::vector<SoftTissue> soft_tissue;  ///< per marker
  double noise_sd_mm = 0.0;
};

/// Stream numbers of the subject's independent random draws.
enum class SubjectStream : std::uint64_t { segments = 11, placement = 12, soft_tissue = 13 };

namespace detail {
// The segment (joint group, or "root") a frame belongs to.
inline std::string segment_of_frame(const body::BodyModel& model, int frame) {
  return frame == 0 ? std::string("root") : model.joints[static_cast<std::size_t>(frame - 1)].group;
}
}  // namespace detail

/// Draws a subject from `base` (any height; it is rescaled to options.height_mm) and `seed`.
/// Every segment is scaled uniformly about its own joint centre: the joint-centre offsets
/// expressed in a segment's frame (its child joints) and the offsets of the markers riding on it
/// are multiplied by the segment's factor.
Subject make_subject(const body::BodyModel& base, const SubjectOptions& options, std::uint64_t seed);

/// The soft-tissue offsets of all markers (3 x markers, mm, each in its own frame) at `pose` and
/// `time_s`.
Eigen::Matrix3Xd soft_tissue_offsets(const Subject& subject, const body::Pose& pose, double time_s);

/// The subject's model at one instant: the placed markers moved by the soft tissue. Forward
/// kinematics of this model at `pose` gives the clean markers of that frame.
body::BodyModel model_at(const Subject& subject, const body::Pose& pose, double time_s);

/// The clean marker positions (3 x markers, mm, lab frame) of the subject at `pose` and `time_s`.
Eigen::Matrix3Xd subject_marker_positions(const Subject& subject, const body::Pose& pose, double time_s);

/// The markers riding on a segment ("root" or a joint group such as "LE", "BT"); throws
/// std::invalid_argument listing the segment names when `segment` is unknown.
inline std::vector<Eigen::Index> markers_of_segment(const Subject& subject, const std::string& segment) {
  const auto found = std::find(subject.segments.begin(), subject.segments.end(), segment);
  if (found == subject.segments.end()) {
    std::string known;
    for (const auto& name : subject.segments) known += (known.empty() ? "" : ", ") + name;
    throw std::invalid_argument("unknown segment '" + segment + "' (segments: " + known + ")");
  }
  const int index = static_cast<int>(found - subject.segments.begin());
  std::vector<Eigen::Index> markers;
  for (std::size_t m = 0; m < subject.marker_segment.size(); ++m)
    if (subject.marker_segment[m] == index) markers.push_back(static_cast<Eigen::Index>(m));
  return markers;
}

}  // namespace s2kf::sim

#if !defined(S2KF_COMPILED)
#include <s2kf/sim/subject.hxx>
#endif
