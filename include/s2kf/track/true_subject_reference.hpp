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
#include <s2kf/track/marker_mapping.hpp>

#include <limits>
#include <stdexcept>

namespace s2kf::track {

/// The true-subject fit of every frame of `recording`, which `subject` was simulated on (its
/// points are the subject's markers in order), as a motion table like the tracker's. A frame
/// without any visible marker has no fit: NaN row (compare_with_truth skips it).
io::MotionTable true_subject_fit(const sim::Subject& subject, const sim::Recording& recording);

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

S2KF_INLINE io::MotionTable true_subject_fit(const sim::Subject& subject, const sim::Recording& recording) {
  if (recording.labels != subject.marker_names ||
      recording.truth.size() != static_cast<std::size_t>(recording.frames()))
    throw std::invalid_argument("true_subject_fit: the recording was not simulated on this subject");
  MarkerMapping mapping;
  for (int m = 0; m < subject.model.marker_count(); ++m) mapping.point_of_marker.push_back(m);
  GradientBaseline fit(subject.model, mapping);
  io::MotionTable table;
  table.joint_names = subject.joint_names;
  table.values.resize(recording.frames(),
                      static_cast<Eigen::Index>(body::kRootValues + subject.joint_names.size()));
  for (Eigen::Index k = 0; k < recording.frames(); ++k) {
    table.frame.push_back(static_cast<long>(k));
    table.time.push_back(recording.time_s(k));
    fit.start_from(recording.truth[static_cast<std::size_t>(k)]);
    const FrameEstimate& e = fit.process(recording.frame(k), recording.visible.col(k));
    if (e.visible_markers > 0)
      body::write_pose_row(e.pose, table.values.row(k).transpose());
    else
      table.values.row(k).setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  return table;
}

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::track
