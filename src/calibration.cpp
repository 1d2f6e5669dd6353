// The compiled copy of the definitions in s2kf/calibration/ (core/compilation_mode.hpp).
#include <s2kf/calibration/calibration_check.hxx>
#include <s2kf/calibration/height_estimate.hxx>
#include <s2kf/calibration/static_stretch.hxx>
#include <s2kf/calibration/static_trial_markers.hxx>
#include <s2kf/calibration/subject_calibration.hxx>
#include <s2kf/calibration/subject_information.hxx>
