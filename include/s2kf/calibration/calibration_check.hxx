/// @file
/// The definitions of <s2kf/calibration/calibration_check.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/calibration/calibration_check.hpp>

namespace s2kf::calibration {
namespace detail {
inline std::string number_text(double value, int precision) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << value;
  return s.str();
}
}  // namespace detail

S2KF_INLINE CalibrationCheck check_calibration(const body::BodyModel& start,
                                               const SubjectCalibration& calibration, bool static_trial,
                                               const CalibrationLimits& limits) {
  CalibrationCheck check;
  const std::string stance =
      static_trial ? "the subject did not stand in the pose assumed (--static-pose), " : "";
  const std::string causes =
      "likely cause: " + stance +
      "a mislabelled marker on or next to it, or a marker set that is not the recording's";
  // Bone lengths: the factor farthest from 1, and the first outside the limits.
  std::string scale_problem;
  for (const auto& [segment, factor] : calibration.segment_scale) {
    const double ratio = factor > 0 ? std::abs(std::log(factor)) : std::numeric_limits<double>::infinity();
    const double worst = check.worst_scale > 0 ? std::abs(std::log(check.worst_scale))
                                               : std::numeric_limits<double>::infinity();
    if (check.worst_scale_segment.empty() || !(ratio <= worst)) {
      check.worst_scale_segment = segment;
      check.worst_scale = factor;
    }
    if (scale_problem.empty() && !(factor > limits.min_scale && factor < limits.max_scale))
      scale_problem = "the bone-length factor of segment " + segment + " came out " +
                      detail::number_text(factor, 2) + " (a person's lies between " +
                      detail::number_text(limits.min_scale, 1) + " and " +
                      detail::number_text(limits.max_scale, 1) + ")";
  }
  // A static trial's two sides of one segment: as long as each other, within a person's asymmetry.
  std::string side_problem;
  for (const auto& [left, left_factor] : calibration.segment_scale) {
    if (!static_trial) break;
    if (left.size() < 2 || left[0] != 'L') continue;
    const auto right = calibration.segment_scale.find("R" + left.substr(1));
    if (right == calibration.segment_scale.end() || !(left_factor > 0 && right->second > 0)) continue;
    if (std::max(left_factor, right->second) / std::min(left_factor, right->second) > limits.max_side_ratio) {
      side_problem = "the bone-length factors of segments " + left + " and " + right->first + " came out " +
                     detail::number_text(left_factor, 2) + " and " + detail::number_text(right->second, 2) +
                     " (a person's two sides differ by less than " +
                     detail::number_text(100 * (limits.max_side_ratio - 1), 0) +
                     " %); likely cause: the limbs were straight, and a static trial shows where a joint "
                     "lies along a straight limb only through the markers next to it (calibrate it together "
                     "with a moving trial: s2kf track MOVING --static STATIC), or a mislabelled marker on "
                     "or next to them";
      break;  // the first pair, in the segments' order
    }
  }
  // Offsets against the marker set's placement, and each marker's residual.
  int far_markers = 0;
  const std::size_t markers = std::min(start.markers.size(), calibration.model.markers.size());
  for (std::size_t m = 0; m < markers; ++m) {
    const double shift = (calibration.model.markers[m].offset - start.markers[m].offset).norm();
    if (!(shift <= check.worst_offset_shift_mm)) {
      check.worst_offset_shift_mm = shift;
      check.worst_offset_marker = calibration.model.markers[m].name;
    }
    if (!(shift <= limits.max_offset_shift_mm)) ++far_markers;
    const double residual = m < calibration.marker_residual_rms_mm.size()
                                ? calibration.marker_residual_rms_mm[m]
                                : std::numeric_limits<double>::quiet_NaN();
    if (std::isfinite(residual) && residual > check.worst_residual_mm) {
      check.worst_residual_mm = residual;
      check.worst_residual_marker = calibration.model.markers[m].name;
    }
  }
  check.rms_mm = calibration.passes.empty() ? std::numeric_limits<double>::quiet_NaN()
                                            : calibration.passes.front().rms_after_mm;
  const auto segment_of = [&](const std::string& marker) {
    for (const body::Marker& entry : calibration.model.markers)
      if (entry.name == marker) return body::segment_of_frame(calibration.model, entry.frame);
    return std::string("?");
  };
  if (!scale_problem.empty()) {
    check.problem = "the calibrated subject is not a person's: " + scale_problem + "; " + causes;
  } else if (!side_problem.empty()) {
    check.problem = "the calibrated subject is not a person's: " + side_problem;
  } else if (far_markers > 0) {
    const std::string marker = check.worst_offset_marker;
    check.problem =
        "the calibrated subject is not a person's: marker " + marker + " came out " +
        detail::number_text(check.worst_offset_shift_mm, 0) +
        " mm from where the marker set puts it on segment " + segment_of(marker) +
        (far_markers > 1 ? " (and " + std::to_string(far_markers - 1) + " more markers beyond " +
                               detail::number_text(limits.max_offset_shift_mm, 0) + " mm)"
                         : "") +
        "; likely cause: " +
        (far_markers > 2
             ? stance + "a marker set that is not the recording's"
             : "marker " + marker + " is mislabelled or not where the marker set puts it" +
                   (static_trial ? ", or the subject did not stand in the pose assumed (--static-pose)"
                                 : ""));
  } else if (!(check.rms_mm <= limits.max_rms_mm)) {
    check.problem = "the calibrated subject does not fit the recording: an RMS marker distance of " +
                    detail::number_text(check.rms_mm, 1) + " mm after adjusting it (at most " +
                    detail::number_text(limits.max_rms_mm, 0) + " mm expected); likely cause: " + stance +
                    "a marker set that is not the recording's";
  } else if (check.worst_residual_mm > limits.max_marker_residual_mm &&
             check.worst_residual_mm > limits.marker_residual_ratio * check.rms_mm) {
    check.problem = "the calibrated subject does not fit marker " + check.worst_residual_marker +
                    " on segment " + segment_of(check.worst_residual_marker) + ": an RMS distance of " +
                    detail::number_text(check.worst_residual_mm, 1) + " mm after adjusting it (at most " +
                    detail::number_text(limits.max_marker_residual_mm, 0) +
                    " mm expected); likely cause: the marker is mislabelled, or came loose and moved";
  }
  return check;
}

}  // namespace s2kf::calibration
