/// @file
/// The check every calibrated subject passes before it is used or written: bone-length factors
/// within the model's limits, marker offsets within a plausible distance of the marker set's
/// placement, residuals a body model can explain. A subject that fails is refused with one
/// sentence naming the segment or marker and the likely cause.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/core/compilation_mode.hpp>

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace s2kf::calibration {

/// What a calibrated subject may be and still be a person wearing the marker set.
struct CalibrationLimits {
  /// A bone-length factor (against the height-scaled model) outside this open range is refused:
  /// the limits a marker-set file's segment_scale must keep (body/marker_set.hpp).
  double min_scale = 0.5, max_scale = 2.0;
  /// A marker farther than this (mm) from the marker set's placement on its segment was not
  /// placed there: mislabelled, or the subject stood otherwise than assumed. Real placements differ
  /// from a set's by more than 10 cm (test1's RELB: 123 mm, calibrated to 3.4 mm), a left-right swap
  /// by 20 cm or more.
  double max_offset_shift_mm = 200;
  /// A marker whose RMS residual in the bundle adjustment stays above this (mm) and above
  /// marker_residual_ratio times the RMS of all does not fit the body as the others do.
  double max_marker_residual_mm = 40;
  double marker_residual_ratio = 3;
  /// The adjusted poses' RMS marker distance (mm) above which the fit explains nothing (the real
  /// 85_02 recording's first 150 frames end at 40 mm and still make a usable subject).
  double max_rms_mm = 60;
  /// A static trial's left and right bone-length factors of one segment (LH and RH, ...) differing
  /// by more than this ratio: a person's sides differ by a few percent, and straight limbs show a
  /// joint's place along them only through the markers next to it (the real Plug-in Gait static
  /// trial alone: thighs 0.79 and 1.04, shanks 1.20 and 0.89; with its moving trial 1.08 and 1.08,
  /// 1.05 and 0.96).
  double max_side_ratio = 1.25;
};

/// What the check measured: the worst of each kind, to report beside the verdict.
struct CalibrationCheck {
  std::string worst_scale_segment;
  double worst_scale = 1;  ///< the factor farthest from 1 (in ratio)
  std::string worst_offset_marker;
  double worst_offset_shift_mm = 0;
  std::string worst_residual_marker;
  double worst_residual_mm = 0;
  double rms_mm = 0;  ///< the last bundle adjustment's RMS after it
  /// Empty when the subject is plausible; else one sentence naming the segment or marker and the
  /// likely cause.
  std::string problem;
};

/// Checks `calibration` (calibrated from `start`, the model the calibration began with: the marker
/// set applied and scaled to the height). `static_trial`: the calibration read a static trial, so a
/// wrong stance is a likely cause.
CalibrationCheck check_calibration(const body::BodyModel& start, const SubjectCalibration& calibration,
                                   bool static_trial, const CalibrationLimits& limits = {});

}  // namespace s2kf::calibration

#if !defined(S2KF_COMPILED)
#include <s2kf/calibration/calibration_check.hxx>
#endif
