/// @file
/// One recording through `s2kf track`: its settings (the command's options), and the work that
/// turns one C3D file into the output files, its summary and the paragraph the command prints.
#pragma once

#include "extra_outputs.hpp"

#include <s2kf/calibration/subject_calibration.hpp>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace s2kf::cli {

struct TrackSettings {
  std::vector<std::string> inputs;
  std::string out;
  double height_mm = 0;  // 0: estimate
  int samples = 0;       // 0: the preset's
  std::string preset = "default";
  std::string motion_model;               // empty: the preset's
  std::string gain = "information-form";  // square-root, information-form-root-products (TrackerOptions)
  std::string method = "s2kf";
  std::string markerset;       // empty: the bundled set that matches best
  std::string subject;         // a calibrated subject file (s2kf calibrate)
  std::string static_trial;    // a static trial: the subject is calibrated on it first (--static)
  double static_sd_deg = 3.0;  // --static-sd
  bool calibrate = true;       // calibrate the subject on the recording first (not with --subject)
  int calibration_frames = 1200;
  double calibration_shrink = calibration::CalibrationOptions{}.weak_direction_shrink;
  bool noise_from_calibration = true;  // false: --uniform-noise
  int calibration_samples = 0;         // the calibration's tracking pass; 0: the tracker's samples
  int calibration_threads = 1;         // set by run_track: every core for one recording, 1 in a batch
  bool smooth = false;
  long figure_frame = -1;  // >= 0: draw this frame
  std::string truth;       // a ground-truth motion CSV (simulated recordings): accuracy in the summary
  bool realtime = false;
  bool quiet = false;
  int jobs = 0;
  std::string shard;       // "I/N": track only the I-th of N parts of the recordings (0-based)
  bool dry_run = false;    // list the recordings and their output prefixes, track nothing
  bool verbose = false;    // also print the seconds per stage
  bool html = false;       // also write PREFIX.html, the interactive 3D page (s2kf view)
  OutputSettings outputs;  // --formats, --bvh-units, --derivatives (extra_outputs.hpp)
};

struct TrackOutcome {
  nlohmann::json summary;
  std::string paragraph;
};

/// Tracks one recording through the library's pipeline (prepare a session, run it) into the
/// output files; returns the summary and the paragraph to print.
TrackOutcome track_file(const std::string& input, const std::string& prefix, const TrackSettings& settings,
                        bool show_progress);

}  // namespace s2kf::cli
