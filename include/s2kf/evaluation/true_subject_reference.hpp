/// @file
/// The reachable reference on a simulated recording: a per-frame least-squares fit of the markers
/// with the subject's own skeleton (its true bone lengths) and its true marker placement, started
/// at the true pose in every frame. A calibration can at best recover that subject, so this fit
/// is what the recording's markers can tell; what it still misses comes from what no fixed subject
/// model explains (soft tissue that moves with the pose, sensor noise) and from hidden markers.
#pragma once

#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>
#include <s2kf/track/gradient_baseline.hpp>
#include <s2kf/body/marker_mapping.hpp>

#include <limits>
#include <stdexcept>

namespace s2kf::evaluation {

/// The true-subject fit of every frame of `recording`, which `subject` was simulated on (its
/// points are the subject's markers in order), as a motion table like the tracker's. A frame
/// without any visible marker has no fit: NaN row (compare_with_truth skips it).
io::MotionTable true_subject_fit(const sim::Subject& subject, const sim::Recording& recording);

/// `subject` with each marker's offset replaced by the mean of where the recording shows it in the
/// frame it rides on, at the true poses: the constant marker placement that fits the recording
/// best (least squares) once every pose is known. Soft tissue's average over the recording is
/// then part of the placement, as it is for any calibration from the recording's markers.
sim::Subject best_constant_placement(const sim::Subject& subject, const sim::Recording& recording);

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

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

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::evaluation
