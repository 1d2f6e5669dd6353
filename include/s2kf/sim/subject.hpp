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

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

S2KF_INLINE Subject make_subject(const body::BodyModel& base, const SubjectOptions& options,
                                 std::uint64_t seed) {
  validate(options);
  base.validate();
  Subject subject;
  subject.height_mm = options.height_mm;
  subject.model = base.scaled(options.height_mm);
  body::BodyModel& model = subject.model;
  subject.joint_names = model.joint_names();
  subject.marker_names = model.marker_names();
  subject.lower = model.lower_limits();
  subject.upper = model.upper_limits();
  subject.noise_sd_mm = options.noise_sd_mm;

  const auto segment_index = [&](const std::string& name) {
    const auto found = std::find(subject.segments.begin(), subject.segments.end(), name);
    if (found != subject.segments.end()) return static_cast<int>(found - subject.segments.begin());
    subject.segments.push_back(name);
    return static_cast<int>(subject.segments.size()) - 1;
  };
  segment_index("root");
  for (const body::Joint& joint : model.joints) segment_index(joint.group);
  for (const body::Marker& marker : model.markers)
    subject.marker_segment.push_back(segment_index(detail::segment_of_frame(model, marker.frame)));

  const auto segment_count = static_cast<Eigen::Index>(subject.segments.size());
  subject.segment_scale = Eigen::VectorXd::Ones(segment_count);
  std::mt19937_64 segment_rng(derive_seed(seed, static_cast<std::uint64_t>(SubjectStream::segments)));
  for (Eigen::Index s = 0; s < segment_count && options.segment_scale_sd > 0.0; ++s)
    subject.segment_scale(s) =
        std::clamp(1.0 + options.segment_scale_sd * standard_normal(segment_rng), 0.85, 1.15);
  for (body::Joint& joint : model.joints)
    joint.translation *=
        subject.segment_scale(segment_index(detail::segment_of_frame(model, joint.parent_frame)));
  for (std::size_t m = 0; m < model.markers.size(); ++m)
    model.markers[m].offset *= subject.segment_scale(subject.marker_segment[m]);

  const auto markers = static_cast<Eigen::Index>(model.markers.size());
  subject.placement = Eigen::Matrix3Xd::Zero(3, markers);
  std::mt19937_64 placement_rng(derive_seed(seed, static_cast<std::uint64_t>(SubjectStream::placement)));
  for (Eigen::Index m = 0; m < markers && options.placement_sd_mm > 0.0; ++m)
    for (int c = 0; c < 3; ++c)
      subject.placement(c, m) = options.placement_sd_mm * standard_normal(placement_rng);
  for (Eigen::Index m = 0; m < markers; ++m)
    model.markers[static_cast<std::size_t>(m)].offset += subject.placement.col(m);

  std::mt19937_64 tissue_rng(derive_seed(seed, static_cast<std::uint64_t>(SubjectStream::soft_tissue)));
  for (const body::Marker& marker : model.markers) {
    std::vector<Eigen::Index> joints;
    const std::string segment = detail::segment_of_frame(model, marker.frame);
    for (int j = 0; j < model.joint_count(); ++j)
      if (model.joints[static_cast<std::size_t>(j)].group == segment && segment != "root")
        joints.push_back(j);
    subject.soft_tissue.push_back(
        options.soft_tissue_mm > 0.0
            ? draw_soft_tissue(joints, options.soft_tissue_mm, tissue_rng)
            : SoftTissue{joints, Eigen::Matrix3Xd::Zero(3, static_cast<Eigen::Index>(joints.size()))});
  }
  return subject;
}

S2KF_INLINE Eigen::Matrix3Xd soft_tissue_offsets(const Subject& subject, const body::Pose& pose,
                                                 double time_s) {
  Eigen::Matrix3Xd offsets(3, static_cast<Eigen::Index>(subject.soft_tissue.size()));
  const Eigen::VectorXd angles = pose.joints;
  for (std::size_t m = 0; m < subject.soft_tissue.size(); ++m)
    offsets.col(static_cast<Eigen::Index>(m)) =
        subject.soft_tissue[m].offset(angles, subject.lower, subject.upper, time_s);
  return offsets;
}

S2KF_INLINE body::BodyModel model_at(const Subject& subject, const body::Pose& pose, double time_s) {
  body::BodyModel model = subject.model;
  const Eigen::Matrix3Xd offsets = soft_tissue_offsets(subject, pose, time_s);
  for (std::size_t m = 0; m < model.markers.size(); ++m)
    model.markers[m].offset += offsets.col(static_cast<Eigen::Index>(m));
  return model;
}

S2KF_INLINE Eigen::Matrix3Xd subject_marker_positions(const Subject& subject, const body::Pose& pose,
                                                      double time_s) {
  return body::marker_positions(model_at(subject, pose, time_s), pose);
}

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::sim
