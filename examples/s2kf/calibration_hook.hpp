/// @file
/// Subject calibration on a C3D recording for the CLI (`s2kf calibrate`, and `s2kf track`, which
/// calibrates on the recording it tracks unless told not to).
#pragma once

#include "command.hpp"
#include "marker_set_json.hpp"

#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/track/subject_calibration.hpp>
#include <s2kf/track/tracker_options.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

namespace s2kf::cli {

/// The first `max_frames` frames of the recording (consecutive, so the tracker can follow them);
/// the reader is left at frame 0.
inline void read_calibration_frames(c3d::C3dReader& reader, std::int64_t max_frames,
                                    std::vector<Eigen::Matrix3Xd>& points,
                                    std::vector<Eigen::Array<bool, Eigen::Dynamic, 1>>& visible) {
  points.clear();
  visible.clear();
  reader.seek_frame(0);
  c3d::Frame frame;
  const std::int64_t count = std::min<std::int64_t>(reader.info().frame_count, max_frames);
  for (std::int64_t f = 0; f < count && reader.read_frame(frame); ++f) {
    points.push_back(frame.positions);
    visible.push_back(frame.visible);
  }
  reader.seek_frame(0);
}

/// Calibrates `model` (the choice's model scaled to the subject's height) on the first
/// `max_frames` frames of the recording. Tracker options are the ones the tracking will use.
inline track::SubjectCalibration calibrate_recording(c3d::C3dReader& reader, const body::BodyModel& model,
                                                     const MarkerSetChoice& choice,
                                                     const track::TrackerOptions& tracker_options,
                                                     double rate_hz, int iterations, std::int64_t max_frames,
                                                     bool final_pass, bool estimate_scales = true) {
  std::vector<Eigen::Matrix3Xd> points;
  std::vector<Eigen::Array<bool, Eigen::Dynamic, 1>> visible;
  read_calibration_frames(reader, max_frames, points, visible);
  track::CalibrationOptions options;
  options.iterations = iterations;
  options.final_pass = final_pass;
  options.estimate_segment_scales = estimate_scales;
  options.marker_weight = calibration_weights(choice.set, tracker_options.marker_noise_mm);
  try {
    return track::calibrate_subject(model, choice.mapping, tracker_options, rate_hz, points, visible,
                                    options);
  } catch (const std::invalid_argument& e) {
    throw UserError(reader.info().labels.empty() ? e.what() : std::string("calibration failed: ") + e.what());
  }
}

}  // namespace s2kf::cli
