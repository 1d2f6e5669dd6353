// One recording through `s2kf track` (track_file.hpp): prepare the library's session, run it into
// the output files, and summarise.
#include "track_file.hpp"

#include <s2kf/app/extra_outputs.hpp>
#include <s2kf/app/frame_reports.hpp>
#include <s2kf/app/track_summary.hpp>
#include "frame_figure.hpp"
#include "front_end.hpp"
#include "interruption.hpp"
#include "viewer/result_page.hpp"  // --html

#include <s2kf/app/track_request.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/instruction_set.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_error.hpp>
#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/io/motion_stream_writer.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/stage_times.hpp>
#include <s2kf/track/tracking_metrics.hpp>

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <numeric>
#include <optional>
#include <sstream>
#include <thread>
#include <tuple>

namespace s2kf::cli {
namespace {

namespace fs = std::filesystem;

}  // namespace

/// Tracks one recording through the library's pipeline (prepare a session, run it) into the
/// output files; returns the summary and the paragraph to print.
TrackOutcome track_file(const std::string& input, const std::string& prefix, const TrackSettings& settings,
                        bool show_progress) {
  throw_if_interrupted();  // a batch stops at the next recording
  const auto stage_start = std::chrono::steady_clock::now();
  std::unique_ptr<c3d::C3dFrameSource> source;
  try {
    source = std::make_unique<c3d::C3dFrameSource>(input);
  } catch (const c3d::C3dError& e) {
    throw UserError(input + ": " + e.sentence());
  } catch (const std::exception& e) {
    throw UserError(e.what());
  }
  const double opening = track::seconds_since(stage_start);
  const c3d::C3dInfo& info = source->info();
  // Everything that can be checked is checked before tracking: a late failure would waste the run.
  if (!c3d::plausible_frame_rate(info.rate))  // the reader gives 0 for none that is a positive number
    throw UserError(input + ": " +
                    (info.rate > 0 ? "the frame rate " + c3d::detail::format_number(info.rate) +
                                         " Hz in its header is not one motion capture runs at (" +
                                         c3d::detail::format_number(c3d::kPlausibleFrameRateHz[0]) + " to " +
                                         c3d::detail::format_number(c3d::kPlausibleFrameRateHz[1]) + " Hz)"
                                   : std::string("no valid frame rate in its header or POINT:RATE")) +
                    "; correct POINT:RATE");
  TrackInput recording;
  recording.name = input;
  recording.stem = fs::path(input).stem().string();
  recording.prepare = source.get();
  recording.frames = source.get();
  recording.rate_hz = info.rate;
  recording.frame_count = info.frame_count;
  for (const c3d::PointLabel& label : info.labels)  // model outputs keep their names in the summary
    recording.raw_labels.push_back(label.model_output ? label.raw : std::string());
  recording.warnings = info.warnings;
  recording.open_seconds = opening;
  return track_source(recording, prefix, settings, show_progress);
}

TrackOutcome track_source(const TrackInput& input, const std::string& prefix, const TrackSettings& settings,
                          bool show_progress, const TrackHooks& extra) {
  track::StageTimes outside;  // stages outside the session and the run: opening, finishing the files
  outside.read = input.open_seconds;
  auto stage_start = std::chrono::steady_clock::now();
  const bool known_length = input.frame_count >= 0;
  if (known_length && settings.figure_frame >= input.frame_count)
    throw UserError(input.name + ": --figure " + std::to_string(settings.figure_frame) + " is beyond its " +
                    std::to_string(input.frame_count) + " frames (0-based)");
  app::RecordingDescription recording;
  recording.input = input.name;
  recording.raw_labels = input.raw_labels;
  recording.file_warnings = input.warnings;
  recording.readable_file = fs::is_regular_file(input.name);  // not a live source (HOST:PORT)
  recording.inferred_markerset_path = prefix + "_markerset.json";
  app::PreparedTrack prepared = app::prepare_track(*input.prepare, recording, settings.request);
  if (settings.placed_for_static) {  // the subject file's set holds them; say which were placed
    prepared.choice.inferred = settings.placed_for_static->inferred;
    prepared.choice.left_out = settings.placed_for_static->left_out;
    prepared.messages = app::marker_set_messages(prepared.choice, prepared.session.mapping);
  }
  const pipeline::Session& session = prepared.session;
  if (extra.on_prepared) extra.on_prepared(session);

  const auto start = std::chrono::steady_clock::now();
  const double frame_period = 1.0 / input.rate_hz;
  long deadline_misses = 0;
  c3d::Frame figure_points;  // the frame --figure draws, as recorded
  pipeline::RunHooks hooks;
  hooks.on_read = [&](const MarkerFrame& frame) {
    throw_if_interrupted();
    if (frame.index == settings.figure_frame) figure_points = frame;
    if (extra.on_read) extra.on_read(frame);
    if (settings.realtime)
      std::this_thread::sleep_until(
          start + std::chrono::duration<double>(static_cast<double>(frame.index) * frame_period));
  };
  hooks.on_frame = [&](long index) {
    if (settings.realtime) {
      const double late = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() -
                          (static_cast<double>(index) + 1) * frame_period;
      if (late > 0) ++deadline_misses;
    }
    if (show_progress && known_length && (index % 25 == 0 || index + 1 == input.frame_count)) {
      const int width = 40;
      const double done = static_cast<double>(index + 1) / static_cast<double>(input.frame_count);
      std::cerr << "\r" << fs::path(input.name).filename().string() << " ["
                << std::string(static_cast<std::size_t>(done * width), '#')
                << std::string(width - static_cast<std::size_t>(done * width), ' ') << "] " << index + 1
                << "/" << input.frame_count << std::flush;
    }
  };
  // Outputs, all or none: every file goes to a temporary name and the whole set is renamed into
  // place by motion_files.finish() at the end, the summary last; a failure or an interrupt before
  // then removes the temporary files and leaves existing outputs as they were. Rows go to the files
  // as they are produced: as tracked (memory stays constant however long the recording is), or
  // after the backward pass with --smooth.
  const std::string& name = input.stem;
  stage_start = std::chrono::steady_clock::now();
  const OpenOutputs open_outputs;  // SIGINT/SIGTERM now wait for throw_if_interrupted()
  io::MotionStreamWriter motion_files(motion_file_paths(prefix, settings.outputs), session.model,
                                      input.rate_hz, name, bvh_units(settings.outputs));
  write_model_outputs(motion_files, settings.outputs, prefix, input.name, session.model,
                      session.mapping);  // .osim, .trc
  outside.writing = track::seconds_since(stage_start);
  std::ostream& marker_report = motion_files.companion(prefix + "_markers.csv");
  write_marker_report_header(marker_report);
  std::ostream& segment_report = motion_files.companion(prefix + "_segments.csv");
  write_segment_report_header(segment_report, session.segments);
  std::optional<body::Pose> figure_pose;  // the pose of frame --figure, when it was tracked
  hooks.sink = [&](const track::TrackedFrame& f) {
    throw_if_interrupted();
    motion_files.append(f.frame, f.time, f.values);
    write_marker_report_row(marker_report, f);
    write_segment_report_row(segment_report, session, f);
    if (f.frame == settings.figure_frame && io::is_tracked_row(f.values))
      figure_pose = body::pose_from_row(f.values);
    if (extra.on_row) extra.on_row(f);
  };
  // A stream of unknown length keeps its summary's per-frame numbers in fixed memory.
  const track::TrackingRun run =
      app::run_track(prepared, *input.frames, settings.request, hooks, !known_length);
  if (show_progress) std::cerr << "\n";
  std::vector<std::string>& warnings = prepared.warnings;
  std::string figure_file;
  if (settings.figure_frame >= 0) {
    std::string problem;
    if (!figure_pose)
      warnings.push_back("frame " + std::to_string(settings.figure_frame) +
                         " was not tracked: no figure drawn");
    else if (draw_tracked_frame(prefix, settings.figure_frame, session.model, session.mapping, *figure_pose,
                                figure_points.positions, figure_points.visible, problem))
      figure_file = prefix + "_frame" + std::to_string(settings.figure_frame) + ".png";
    else
      warnings.push_back(problem);
  }

  // Accuracy against the truth from the motion as written, read back before the set is committed.
  std::optional<io::MotionTable> written;
  if (prepared.truth) {
    try {
      written = io::load_motion_csv(motion_files.flushed_csv());
    } catch (const std::invalid_argument& e) {
      throw UserError("--truth: " + settings.request.truth + ": " + e.what());
    }
  }
  // --static: the subject calibrated on the static trial and this recording, for --subject.
  const std::optional<nlohmann::json> subject = app::joint_subject_document(
      prepared, run, settings.request, fs::path(prefix).filename().string() + "_subject");
  if (subject) motion_files.companion(prefix + "_subject.json") << subject->dump(2) << "\n";
  nlohmann::json summary =
      app::summarize_track(prepared, run, settings.request, written ? &*written : nullptr, outside);
  if (settings.realtime) summary["deadline_misses"] = deadline_misses;
  if (extra.on_summary) extra.on_summary(summary);
  // Labels and file names are UTF-8 (the reader decodes Latin-1); anything else is replaced, never
  // a reason to lose the run.
  motion_files.companion(prefix + ".json")
      << summary.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  throw_if_interrupted();
  motion_files.finish();
  if (settings.html)
    viewer::write_result_page(prefix, session.model, session.mapping, settings.request.truth);  // --html

  std::ostringstream paragraph;
  paragraph << track_paragraph(summary, name);
  if (!warnings.empty())
    paragraph << " " << warnings.size() << " warning(s), listed in " << prefix << ".json.";
  paragraph << "\n" << written_files_sentence(prefix, settings.outputs);
  if (subject) paragraph << ", the subject " << prefix << "_subject.json";
  if (settings.html) paragraph << ", the 3D page " << prefix << ".html";
  if (!figure_file.empty()) paragraph << ", and the figure " << figure_file;
  paragraph << ".";
  if (settings.verbose) {
    const track::StageTimes times = session.times + run.times + outside;  // as in the summary
    paragraph << "\nSeconds per stage:";
    for (const auto& [stage, seconds] : track::stage_list(times))
      paragraph << " " << stage << " " << fixed_text(seconds, 3) << (stage == "writing" ? "" : ",");
    paragraph << " (" << fixed_text(times.sum(), 3) << " in all), " << instruction_set_text() << ".";
  }
  return {summary, paragraph.str()};
}

}  // namespace s2kf::cli
