/// @file
/// The definitions of <s2kf/evaluation/true_subject_reference.hpp>: inline where the library is used
/// header-only, compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/evaluation/true_subject_reference.hpp>

namespace s2kf::evaluation {

S2KF_INLINE io::MotionTable true_subject_fit(const sim::Subject& subject, const sim::Recording& recording) {
  if (recording.labels != subject.marker_names ||
      recording.truth.size() != static_cast<std::size_t>(recording.frames()))
    throw std::invalid_argument("true_subject_fit: the recording was not simulated on this subject");
  body::MarkerMapping mapping;
  for (int m = 0; m < subject.model.marker_count(); ++m) mapping.point_of_marker.push_back(m);
  track::GradientBaseline fit(subject.model, mapping);
  io::MotionTable table;
  table.joint_names = subject.joint_names;
  table.values.resize(recording.frames(),
                      static_cast<Eigen::Index>(body::kRootValues + subject.joint_names.size()));
  for (Eigen::Index k = 0; k < recording.frames(); ++k) {
    table.frame.push_back(static_cast<long>(k));
    table.time.push_back(recording.time_s(k));
    fit.start_from(recording.truth[static_cast<std::size_t>(k)]);
    const track::FrameEstimate& e = fit.process(recording.frame(k), recording.visible.col(k));
    if (e.visible_markers > 0)
      body::write_pose_row(e.pose, table.values.row(k).transpose());
    else
      table.values.row(k).setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  return table;
}

S2KF_INLINE sim::Subject best_constant_placement(const sim::Subject& subject,
                                                 const sim::Recording& recording) {
  if (recording.labels != subject.marker_names ||
      recording.truth.size() != static_cast<std::size_t>(recording.frames()))
    throw std::invalid_argument("best_constant_placement: the recording was not simulated on this subject");
  const body::BodyModel& model = subject.model;
  Eigen::Matrix3Xd sum = Eigen::Matrix3Xd::Zero(3, model.marker_count());
  Eigen::VectorXd count = Eigen::VectorXd::Zero(model.marker_count());
  for (Eigen::Index k = 0; k < recording.frames(); ++k) {
    const body::FrameTransforms tf = body::joint_frames(model, recording.truth[static_cast<std::size_t>(k)]);
    const auto y = recording.frame(k);
    for (int m = 0; m < model.marker_count(); ++m) {
      if (!recording.visible(m, k) || !y.col(m).allFinite()) continue;
      const auto f = static_cast<std::size_t>(model.markers[static_cast<std::size_t>(m)].frame);
      sum.col(m) += tf.rotations[f].transpose() * (y.col(m) - tf.origins[f]);
      count[m] += 1;
    }
  }
  sim::Subject fitted = subject;
  for (int m = 0; m < model.marker_count(); ++m)
    if (count[m] > 0) fitted.model.markers[static_cast<std::size_t>(m)].offset = sum.col(m) / count[m];
  return fitted;
}

}  // namespace s2kf::evaluation
