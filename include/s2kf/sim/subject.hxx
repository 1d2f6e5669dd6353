/// @file
/// The definitions of <s2kf/sim/subject.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/sim/subject.hpp>

namespace s2kf::sim {

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

}  // namespace s2kf::sim
