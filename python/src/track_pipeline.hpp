/// @file
/// s2kf.track's work without Python: a recording through the library's pipeline as `s2kf track`
/// runs it (track_pipeline.cpp), for track_bindings.cpp to wrap.
#pragma once

#include <s2kf/core/sample_set.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/track/tracking_run.hpp>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace s2kf::python {

/// s2kf.track's keyword arguments (the program's options of the same names).
struct TrackSettings {
  std::string markerset, subject;
  std::string static_trial;    // a static trial: the subject is calibrated on it first
  double static_sd_deg = 3.0;  // how far each joint may be from the zero pose there
  bool calibrate = true;
  std::int64_t calibration_frames = 1200;
  double calibration_shrink = calibration::CalibrationOptions{}.weak_direction_shrink;
  bool uniform_noise = false;  // true: every marker the tracker's noise (else from the calibration)
  bool smooth = false;
  int samples = 301;
  double height_mm = 0;
  std::string preset = "default";
  std::string gain = "information-form";  // square-root, information-form-root-products
  std::string method = "s2kf";
};

/// A tracked recording: the session it was tracked with, the run, and the program's summary.
struct TrackResult {
  std::string name;  // the .mot file's first line: the recording's file stem
  pipeline::Session session;
  track::TrackingRun run;
  SampleSet samples;
  std::vector<std::string> messages;
  nlohmann::json summary;
  Eigen::Index point_count = 0;
};

/// The pipeline of `s2kf track` (apps/s2kf/command_track.cpp, track_file) without its files:
/// marker-set choice, session, run, summary. `input` names the recording in messages and the
/// summary; `raw_labels` (empty, or one per point) give model outputs their names in the ignored
/// list; `file_warnings` are the C3D reader's. Runs without the GIL; errors are std exceptions
/// or cli::UserError, translated by the caller.
std::unique_ptr<TrackResult> run_pipeline(FrameSource& source, const std::string& input,
                                          const std::string& name, const std::vector<std::string>& raw_labels,
                                          const std::vector<std::string>& file_warnings,
                                          const TrackSettings& settings);

}  // namespace s2kf::python
