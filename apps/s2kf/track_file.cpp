// One recording through `s2kf track` (track_file.hpp): prepare the library's session, run it into
// the output files, and summarise.
#include "track_file.hpp"

#include "command.hpp"
#include "extra_outputs.hpp"
#include "frame_figure.hpp"
#include "frame_reports.hpp"
#include "inferred_marker_set.hpp"
#include "interruption.hpp"
#include "marker_set_json.hpp"
#include "track_summary.hpp"
#include "tracker_samples.hpp"
#include "viewer/result_page.hpp"  // --html

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
#include <s2kf/evaluation/truth_metrics.hpp>

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

/// Memory the smoother may take before --smooth refuses a recording (it keeps every frame's
/// 46-state posterior, TrackingSmoother::kBytesPerFrame, about 17 KB).
constexpr double kSmoothingMemoryLimitBytes = 8e9;

/// Frames left out of the accuracy against the truth (the filter's start-up).
constexpr long kTruthWarmupFrames = 20;

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
  for (const c3d::PointLabel& label : info.labels)
    if (label.model_output) recording.model_outputs.push_back(label.raw);
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
  // Ground truth, read before tracking so a wrong file fails fast.
  std::optional<io::MotionTable> truth;
  if (!settings.truth.empty()) {
    try {
      truth = io::load_motion_csv(settings.truth);
    } catch (const std::exception& e) {
      throw UserError(std::string("--truth: ") + e.what());
    }
    if (known_length && truth->frames() != input.frame_count)
      throw UserError("--truth: " + settings.truth + " has " + std::to_string(truth->frames()) +
                      " rows, but " + input.name + " has " + std::to_string(input.frame_count) + " frames");
  }
  const bool with_rates =
      settings.motion_model.empty()
          ? track::TrackerOptions{}.motion_model == track::MotionModel::constant_velocity
          : track::motion_model_from_name(settings.motion_model) == track::MotionModel::constant_velocity;
  const double smoothing_bytes = static_cast<double>(std::max<std::int64_t>(0, input.frame_count)) *
                                 static_cast<double>(track::TrackingSmoother::bytes_per_frame(with_rates));
  if (settings.smooth && smoothing_bytes > kSmoothingMemoryLimitBytes)
    throw UserError(input.name + ": " + std::to_string(input.frame_count) +
                    " frames are too many to smooth in memory (" + fixed_text(smoothing_bytes / 1e9, 1) +
                    " GB); track without --smooth, or split the recording");
  if (known_length && settings.figure_frame >= input.frame_count)
    throw UserError(input.name + ": --figure " + std::to_string(settings.figure_frame) + " is beyond its " +
                    std::to_string(input.frame_count) + " frames (0-based)");

  const MarkerSetChoice choice = choose_or_infer_marker_set(
      input.name, input.prepare->labels(), settings.markerset, settings.subject, prefix + "_markerset.json");
  pipeline::SessionOptions session_options;
  try {
    session_options.tracker = track::preset_options(settings.preset, input.rate_hz);
  } catch (const std::invalid_argument& e) {
    throw UserError(e.what());
  }
  if (settings.samples > 0) session_options.tracker.samples = settings.samples;
  if (!settings.motion_model.empty())
    session_options.tracker.motion_model = track::motion_model_from_name(settings.motion_model);
  track::set_gain_from_name(session_options.tracker, settings.gain);
  session_options.height_mm = settings.height_mm;
  session_options.calibrate = settings.calibrate && settings.subject.empty();
  session_options.calibration_frames = settings.calibration_frames;
  session_options.calibration.weak_direction_shrink = settings.calibration_shrink;
  session_options.noise_from_calibration = settings.noise_from_calibration;
  session_options.calibration.threads = settings.calibration_threads;
  const SampleSet samples = cached_sample_set(46, session_options.tracker.samples);
  if (session_options.calibrate && settings.calibration_samples > 0 &&
      settings.calibration_samples != session_options.tracker.samples)
    session_options.calibration_samples = cached_sample_set(46, settings.calibration_samples);
  pipeline::Session session;
  try {
    session = pipeline::prepare_session(*input.prepare, choice.set, session_options, samples);
  } catch (const std::invalid_argument& e) {
    throw UserError(input.name + ": " + e.what());
  }
  if (truth && truth->joint_names != session.model.joint_names())
    throw UserError(
        "--truth: " + settings.truth + " does not have the " + std::to_string(session.model.joint_count()) +
        " joint columns of the body model (write it with s2kf simulate, whose _truth.csv has them)");
  // Model outputs never match a marker; the summary lists them under their names in the file.
  // (ignored labels keep the file's order, so the k-th empty one is the k-th model output).
  auto empty = session.mapping.ignored_labels.begin();
  for (const std::string& model_output : input.model_outputs) {
    empty = std::find(empty, session.mapping.ignored_labels.end(), std::string());
    if (empty != session.mapping.ignored_labels.end()) *empty++ = model_output;
  }
  std::vector<std::string> warnings = input.warnings;
  warnings.insert(warnings.end(), session.warnings.begin(), session.warnings.end());
  const std::vector<std::string> messages = marker_set_messages(choice, session.mapping);

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
  pipeline::RunOptions run_options;
  run_options.method = settings.method == "s2kf" ? pipeline::Method::s2kf : pipeline::Method::baseline;
  run_options.smooth = settings.smooth;
  track::TrackingRun run;
  try {
    run = pipeline::run_session(session, *input.frames, samples, run_options, hooks);
  } catch (const std::invalid_argument& e) {
    throw UserError(input.name + ": " + e.what());
  }
  if (show_progress) std::cerr << "\n";
  if (run.frames_tracked == 0)
    throw UserError(input.name + ": no frame has the " +
                    std::to_string(session.tracker.min_markers_to_start) +
                    " visible markers needed to start tracking");
  if (2 * run.frames_prediction_only > run.frames_tracked)
    throw UserError(input.name + ": the filter's update failed in " +
                    std::to_string(run.frames_prediction_only) + " of " + std::to_string(run.frames_tracked) +
                    " tracked frames, which only repeat its prediction; no result is written (" +
                    (run.warnings.empty() ? std::string("see the header and labels") : run.warnings.front()) +
                    ")");
  warnings.insert(warnings.end(), run.warnings.begin(), run.warnings.end());
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

  // Accuracy against the truth, from the motion as written (frames from the 20th on), read back
  // before the set is committed.
  std::optional<evaluation::TruthComparison> accuracy;
  if (truth) {
    try {
      accuracy = evaluation::compare_with_truth(session.model, io::load_motion_csv(motion_files.flushed_csv()),
                                           *truth, kTruthWarmupFrames);
    } catch (const std::invalid_argument& e) {
      throw UserError("--truth: " + settings.truth + ": " + e.what());
    }
  }
  nlohmann::json summary = track_summary(input.name, settings.method, choice, messages, session, run,
                                         settings.smooth, warnings, settings.calibration_shrink, outside);
  if (settings.realtime) summary["deadline_misses"] = deadline_misses;
  if (accuracy) {
    summary["truth"] = truth_json(*accuracy);
    summary["truth"]["warmup_frames"] = kTruthWarmupFrames;
  }
  if (extra.on_summary) extra.on_summary(summary);
  // Labels and file names are UTF-8 (the reader decodes Latin-1); anything else is replaced, never
  // a reason to lose the run.
  motion_files.companion(prefix + ".json")
      << summary.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  throw_if_interrupted();
  motion_files.finish();
  if (settings.html)
    viewer::write_result_page(prefix, session.model, session.mapping, settings.truth);  // --html

  std::ostringstream paragraph;
  paragraph << track_paragraph(summary, name);
  if (!warnings.empty())
    paragraph << " " << warnings.size() << " warning(s), listed in " << prefix << ".json.";
  paragraph << "\n" << written_files_sentence(prefix, settings.outputs);
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
