/// @file
/// One recording through `s2kf track`: its settings (the command's options), and the work that
/// turns a recording (a C3D file, or a stream for `s2kf live`) into the output files, its summary
/// and the paragraph the command prints.
#pragma once

#include <s2kf/app/extra_outputs.hpp>
#include <s2kf/app/track_request.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/track/tracking_run.hpp>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace s2kf::cli {

/// `s2kf track`'s options: the tracking request (app::TrackRequest, shared with Python) and what is
/// the program's own: files, printing, pacing, the batch.
struct TrackSettings {
  std::vector<std::string> inputs;
  std::string out;
  app::TrackRequest request;  // marker set, subject, calibration, tracker, smoothing, truth
  long figure_frame = -1;     // >= 0: draw this frame
  bool realtime = false;
  bool quiet = false;
  int jobs = 0;
  std::string shard;            // "I/N": track only the I-th of N parts of the recordings (0-based)
  bool dry_run = false;         // list the recordings and their output prefixes, track nothing
  bool verbose = false;         // also print the seconds per stage
  bool html = false;            // also write PREFIX.html, the interactive 3D page (s2kf view)
  app::OutputSettings outputs;  // --formats, --bvh-units, --derivatives (app/extra_outputs.hpp)
  // --static: the markers the set does not name, placed by the first recording's motion before the
  // static trial was calibrated with them; each summary lists them.
  std::optional<app::MarkerSetChoice> placed_for_static;
};

struct TrackOutcome {
  nlohmann::json summary;
  std::string paragraph;
};

/// What track_source needs of a recording: the frames to prepare the session on and the frames to
/// track (the same source for a file; a first stretch and the stream for s2kf live), and what is
/// known about them.
struct TrackInput {
  std::string name;                ///< in front of errors and in the summary: a path, or HOST:PORT
  std::string stem;                ///< the motion's name in the files (BVH)
  FrameSource* prepare = nullptr;  ///< frames the height and the calibration are taken from
  FrameSource* frames = nullptr;   ///< frames tracked, read in order until read() says false
  double rate_hz = 0;
  std::int64_t frame_count = -1;        ///< -1: not known in advance (a stream)
  std::vector<std::string> raw_labels;  ///< one per point, model outputs (C3D) named, others empty; or none
  std::vector<std::string> warnings;
  double open_seconds = 0;  ///< spent opening the source (the summary's read stage)
};

/// What a caller adds to a run: the prepared session (its model and marker mapping), each frame as
/// read, each row after it went to the files, and the summary before it is written.
struct TrackHooks {
  std::function<void(const pipeline::Session&)> on_prepared;
  std::function<void(const MarkerFrame&)> on_read;
  std::function<void(const track::TrackedFrame&)> on_row;
  std::function<void(nlohmann::json&)> on_summary;
};

/// Tracks a recording through the application layer (prepare a session, run it) into the output
/// files, all or none; returns the summary and the paragraph to print.
TrackOutcome track_source(const TrackInput& input, const std::string& prefix, const TrackSettings& settings,
                          bool show_progress, const TrackHooks& hooks = {});

/// Tracks one C3D file (track_source on it); returns the summary and the paragraph to print.
TrackOutcome track_file(const std::string& input, const std::string& prefix, const TrackSettings& settings,
                        bool show_progress);

}  // namespace s2kf::cli
