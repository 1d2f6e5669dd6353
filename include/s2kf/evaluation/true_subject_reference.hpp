/// @file
/// The reachable reference on a simulated recording: a per-frame least-squares fit of the markers
/// with the subject's own skeleton (its true bone lengths) and its true marker placement, started
/// at the true pose in every frame. A calibration can at best recover that subject, so this fit
/// is what the recording's markers can tell; what it still misses comes from what no fixed subject
/// model explains (soft tissue that moves with the pose, sensor noise) and from hidden markers.
#pragma once

#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>
#include <s2kf/track/gradient_baseline.hpp>

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

}  // namespace s2kf::evaluation

#if !defined(S2KF_COMPILED)
#include <s2kf/evaluation/true_subject_reference.hxx>
#endif
