/// @file
/// A tracking request without a static trial: a stretch of the recording in which the subject
/// stands still in a reference pose is its static trial (calibration/static_stretch.hpp), calibrated
/// together with the recording (pipeline::SessionOptions::static_trial) once a calibration on the
/// stretch alone has shown it is one (a posture near a reference pose, a subject that passes the check).
#pragma once

#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/app/track_request.hpp>

#include <s2kf/body/marker_set.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/io/frame_source.hpp>

#include <optional>
#include <string>

namespace s2kf::app {

struct StretchSubject {
  std::optional<body::MarkerSet> subject;  ///< calibrated on the stretch alone; none: no static stretch used
  std::string message;                     ///< what was found and used, or why a still stretch was not
  MarkerSequence frames;                   ///< the stretch's frames, when used
};

/// Joint angles (degrees) the posture held on a stretch may be off its reference pose, at most, for
/// the stretch to count as a static trial: beyond that the subject merely stood still.
inline constexpr double kStaticStretchMaxJointOffsetDeg = 25.0;

/// Looks for the static stretch of `source` (`input` names it) among the markers of `choice` and
/// calibrates the subject there as a static trial with the request's static pose, SD and posture,
/// on `threads` threads.
StretchSubject static_stretch_subject(FrameSource& source, const std::string& input,
                                      const MarkerSetChoice& choice, const TrackRequest& request,
                                      const SampleSet& samples, int threads);

}  // namespace s2kf::app
