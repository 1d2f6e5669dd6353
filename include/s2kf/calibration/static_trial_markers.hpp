/// @file
/// Which of a static trial's markers are the recording's: a label names the same marker in both
/// trials only if that marker keeps its distances to the other markers on its segment. Labels a
/// capture system gives unidentified points (Vicon Nexus's `*115`, numbered afresh in every trial)
/// name other markers in each trial, and a marker re-placed between the trials has moved.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/marker_sequence.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>
#include <vector>

namespace s2kf::calibration {

/// A static trial's marker whose distances to its segment's markers are not the recording's.
struct MovedMarker {
  int marker = -1;  ///< model marker
  /// |static trial's - recording's distance| over its pairs on its frame (the median against named
  /// markers, else the RMS); NaN: no pair to judge it by
  double mismatch_mm = 0;
};

/// The model markers not `named` (by the marker set: the same label is the same landmark in every
/// trial) that both trials show and whose label the distances to the other markers on the same
/// model frame do not confirm (each distance the median over the frames showing both markers; they
/// agree within `tolerance_mm`). A marker with two or more named markers on its frame is judged
/// against them (the median); the others against every marker on their frame, the one at odds with the
/// most left out first and the rest judged again without it; one of those is confirmed only by two
/// markers that agree with it (a single distance matches by chance too often), else left out with
/// its RMS, or NaN without any pair to judge it by. 30 mm: soft tissue and another posture change a
/// segment's distances by 10-20 mm, another marker under the label by far more (Nexus's renumbered
/// points in the bundled Plug-in Gait pair: 44-1400 mm).
std::vector<MovedMarker> markers_moved_between_trials(
    const body::BodyModel& model, const body::MarkerMapping& static_mapping,
    const MarkerSequence& static_trial, const body::MarkerMapping& recording_mapping,
    const MarkerSequence& recording, const std::vector<bool>& named, double tolerance_mm = 30.0);

}  // namespace s2kf::calibration

#if !defined(S2KF_COMPILED)
#include <s2kf/calibration/static_trial_markers.hxx>
#endif
