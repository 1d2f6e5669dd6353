// `s2kf track`: stream C3D recordings through the S2KF tracker and write the motion as CSV, OpenSim
// .mot, BVH, a JSON summary and a per-frame marker report.
#include "command.hpp"
#include "extra_outputs.hpp"
#include "frame_figure.hpp"
#include "frame_reports.hpp"
#include "inferred_marker_set.hpp"
#include "interruption.hpp"
#include "marker_set_json.hpp"
#include "recording_batch.hpp"
#include "track_summary.hpp"
#include "tracker_samples.hpp"
#include "viewer/result_page.hpp"  // --html

#include <s2kf/body/pose.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_error.hpp>
#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/io/motion_stream_writer.hpp>
#include <s2kf/track/session.hpp>
#include <s2kf/track/stage_times.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/truth_metrics.hpp>

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

struct TrackSettings {
  std::vector<std::string> inputs;
  std::string out;
  double height_mm = 0;  // 0: estimate
  int samples = 0;       // 0: the preset's
  std::string preset = "default";
  std::string motion_model;  // empty: the preset's
  std::string method = "s2kf";
  std::string markerset;  // empty: the bundled set that matches best
  std::string subject;    // a calibrated subject file (s2kf calibrate)
  bool calibrate = true;  // calibrate the subject on the recording first (not with --subject)
  int calibration_frames = 1200;
  double calibration_shrink = track::CalibrationOptions{}.weak_direction_shrink;
  int calibration_threads = 1;  // set by run_track: every core for one recording, 1 in a batch
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

/// Memory the smoother may take before --smooth refuses a recording (it keeps every frame's
/// 46-state posterior, TrackingSmoother::kBytesPerFrame, about 17 KB).
constexpr double kSmoothingMemoryLimitBytes = 8e9;

/// Frames left out of the accuracy against the truth (the filter's start-up).
constexpr long kTruthWarmupFrames = 20;

struct TrackOutcome {
  nlohmann::json summary;
  std::string paragraph;
};

/// Tracks one recording through the library's pipeline (prepare a session, run it) into the
/// output files; returns the summary and the paragraph to print.
TrackOutcome track_file(const std::string& input, const std::string& prefix, const TrackSettings& settings,
                        bool show_progress) {
  throw_if_interrupted();     // a batch stops at the next recording
  track::StageTimes outside;  // stages outside the session and the run: opening, finishing the files
  auto stage_start = std::chrono::steady_clock::now();
  std::unique_ptr<c3d::C3dFrameSource> source;
  try {
    source = std::make_unique<c3d::C3dFrameSource>(input);
  } catch (const c3d::C3dError& e) {
    throw UserError(input + ": " + e.sentence());
  } catch (const std::exception& e) {
    throw UserError(e.what());
  }
  outside.read = track::seconds_since(stage_start);
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
  // Ground truth, read before tracking so a wrong file fails fast.
  std::optional<io::MotionTable> truth;
  if (!settings.truth.empty()) {
    try {
      truth = io::load_motion_csv(settings.truth);
    } catch (const std::exception& e) {
      throw UserError(std::string("--truth: ") + e.what());
    }
    if (truth->frames() != info.frame_count)
      throw UserError("--truth: " + settings.truth + " has " + std::to_string(truth->frames()) +
                      " rows, but " + input + " has " + std::to_string(info.frame_count) + " frames");
  }
  const bool with_rates =
      settings.motion_model.empty()
          ? track::TrackerOptions{}.motion_model == track::MotionModel::constant_velocity
          : track::motion_model_from_name(settings.motion_model) == track::MotionModel::constant_velocity;
  const double smoothing_bytes = static_cast<double>(info.frame_count) *
                                 static_cast<double>(track::TrackingSmoother::bytes_per_frame(with_rates));
  if (settings.smooth && smoothing_bytes > kSmoothingMemoryLimitBytes)
    throw UserError(input + ": " + std::to_string(info.frame_count) +
                    " frames are too many to smooth in memory (" + fixed_text(smoothing_bytes / 1e9, 1) +
                    " GB); track without --smooth, or split the recording");
  if (settings.figure_frame >= info.frame_count)
    throw UserError(input + ": --figure " + std::to_string(settings.figure_frame) + " is beyond its " +
                    std::to_string(info.frame_count) + " frames (0-based)");

  const MarkerSetChoice choice = choose_or_infer_marker_set(input, source->labels(), settings.markerset,
                                                            settings.subject, prefix + "_markerset.json");
  track::SessionOptions session_options;
  try {
    session_options.tracker = track::preset_options(settings.preset, info.rate);
  } catch (const std::invalid_argument& e) {
    throw UserError(e.what());
  }
  if (settings.samples > 0) session_options.tracker.samples = settings.samples;
  if (!settings.motion_model.empty())
    session_options.tracker.motion_model = track::motion_model_from_name(settings.motion_model);
  session_options.height_mm = settings.height_mm;
  session_options.calibrate = settings.calibrate && settings.subject.empty();
  session_options.calibration_frames = settings.calibration_frames;
  session_options.calibration.weak_direction_shrink = settings.calibration_shrink;
  session_options.calibration.threads = settings.calibration_threads;
  const SampleSet samples = cached_sample_set(46, session_options.tracker.samples);
  track::Session session;
  try {
    session = track::prepare_session(*source, choice.set, session_options, samples);
  } catch (const std::invalid_argument& e) {
    throw UserError(input + ": " + e.what());
  }
  if (truth && truth->joint_names != session.model.joint_names())
    throw UserError(
        "--truth: " + settings.truth + " does not have the " + std::to_string(session.model.joint_count()) +
        " joint columns of the body model (write it with s2kf simulate, whose _truth.csv has them)");
  // Model outputs never match a marker; the summary lists them under their names in the file.
  // (ignored labels keep the file's order, so the k-th empty one is the k-th model output).
  auto empty = session.mapping.ignored_labels.begin();
  for (const c3d::PointLabel& label : info.labels)
    if (label.model_output) {
      empty = std::find(empty, session.mapping.ignored_labels.end(), std::string());
      if (empty != session.mapping.ignored_labels.end()) *empty++ = label.raw;
    }
  std::vector<std::string> warnings = info.warnings;
  warnings.insert(warnings.end(), session.warnings.begin(), session.warnings.end());
  const std::vector<std::string> messages = marker_set_messages(choice, session.mapping);

  const auto start = std::chrono::steady_clock::now();
  const double frame_period = 1.0 / info.rate;
  long deadline_misses = 0;
  c3d::Frame figure_points;  // the frame --figure draws, as recorded
  track::RunHooks hooks;
  hooks.on_read = [&](const MarkerFrame& frame) {
    throw_if_interrupted();
    if (frame.index == settings.figure_frame) figure_points = frame;
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
    if (show_progress && (index % 25 == 0 || index + 1 == info.frame_count)) {
      const int width = 40;
      const double done = static_cast<double>(index + 1) / static_cast<double>(info.frame_count);
      std::cerr << "\r" << fs::path(input).filename().string() << " ["
                << std::string(static_cast<std::size_t>(done * width), '#')
                << std::string(width - static_cast<std::size_t>(done * width), ' ') << "] " << index + 1
                << "/" << info.frame_count << std::flush;
    }
  };
  // Outputs, all or none: every file goes to a temporary name and the whole set is renamed into
  // place by motion_files.finish() at the end, the summary last; a failure or an interrupt before
  // then removes the temporary files and leaves existing outputs as they were. Rows go to the files
  // as they are produced: as tracked (memory stays constant however long the recording is), or
  // after the backward pass with --smooth.
  const std::string name = fs::path(input).stem().string();
  stage_start = std::chrono::steady_clock::now();
  const OpenOutputs open_outputs;  // SIGINT/SIGTERM now wait for throw_if_interrupted()
  io::MotionStreamWriter motion_files(motion_file_paths(prefix, settings.outputs), session.model, info.rate,
                                      name, bvh_units(settings.outputs));
  write_model_outputs(motion_files, settings.outputs, prefix, input, session.model,
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
  };
  track::RunOptions run_options;
  run_options.method = settings.method == "s2kf" ? track::Method::s2kf : track::Method::baseline;
  run_options.smooth = settings.smooth;
  track::TrackingRun run;
  try {
    run = track::run_session(session, *source, samples, run_options, hooks);
  } catch (const std::invalid_argument& e) {
    throw UserError(input + ": " + e.what());
  }
  if (show_progress) std::cerr << "\n";
  if (run.frames_tracked == 0)
    throw UserError(input + ": no frame has the " + std::to_string(session.tracker.min_markers_to_start) +
                    " visible markers needed to start tracking");
  if (2 * run.frames_prediction_only > run.frames_tracked)
    throw UserError(input + ": the filter's update failed in " + std::to_string(run.frames_prediction_only) +
                    " of " + std::to_string(run.frames_tracked) +
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
  std::optional<track::TruthComparison> accuracy;
  if (truth) {
    try {
      accuracy = track::compare_with_truth(session.model, io::load_motion_csv(motion_files.flushed_csv()),
                                           *truth, kTruthWarmupFrames);
    } catch (const std::invalid_argument& e) {
      throw UserError("--truth: " + settings.truth + ": " + e.what());
    }
  }
  nlohmann::json summary = track_summary(input, settings.method, choice, messages, session, run,
                                         settings.smooth, warnings, settings.calibration_shrink, outside);
  if (settings.realtime) summary["deadline_misses"] = deadline_misses;
  if (accuracy) {
    summary["truth"] = truth_json(*accuracy);
    summary["truth"]["warmup_frames"] = kTruthWarmupFrames;
  }
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
    paragraph << " (" << fixed_text(times.sum(), 3) << " in all).";
  }
  return {summary, paragraph.str()};
}

void run_track(const TrackSettings& settings) {
  if (!settings.markerset.empty() && !settings.subject.empty())
    throw UserError("give --markerset or --subject, not both (a subject file is a calibrated marker set)");
  if (settings.smooth && settings.method != "s2kf")
    throw UserError("--smooth works on the S2KF's estimates; it cannot be combined with --method baseline");
  const std::vector<Recording> recordings = find_recordings(settings.inputs);
  const bool batch = recordings.size() > 1 || !settings.shard.empty() ||
                     std::any_of(settings.inputs.begin(), settings.inputs.end(),
                                 [](const std::string& input) { return fs::is_directory(input); });
  if (recordings.size() > 1 && !settings.truth.empty())
    throw UserError("--truth belongs to one recording; track that recording on its own");
  const std::vector<Recording> todo =
      settings.shard.empty() ? recordings : shard_of(recordings, settings.shard);
  // --out is a folder for a batch, and for one recording when it is one or ends in '/'; else the
  // prefix of the one recording's files.
  const bool out_is_folder =
      batch || (!settings.out.empty() && (settings.out.back() == '/' || fs::is_directory(settings.out)));
  const std::vector<std::string> prefixes = output_prefixes(todo, settings.out, out_is_folder);
  check_outputs(settings.outputs, prefixes, !settings.truth.empty());
  if (settings.dry_run || todo.empty()) {
    if (todo.empty() && !settings.quiet)
      std::cout << "shard " << settings.shard << " holds none of the " << recordings.size()
                << " recordings\n";
    for (std::size_t i = 0; i < todo.size(); ++i) std::cout << todo[i].input << " -> " << prefixes[i] << "\n";
    return;
  }
  if (!batch) {
    if (fs::path(prefixes[0]).has_parent_path()) fs::create_directories(fs::path(prefixes[0]).parent_path());
    const bool terminal = isatty(STDERR_FILENO) && !settings.quiet;
    TrackSettings one = settings;  // one recording: its calibration may take every core
    one.calibration_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const TrackOutcome outcome = track_file(todo[0].input, prefixes[0], one, terminal);
    if (!settings.quiet) std::cout << outcome.paragraph << "\n";
    return;
  }
  // A batch: one recording per thread. A recording that fails is reported (its line names it, its
  // PREFIX.json records why) and the others go on; the exit status says that some failed.
  const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  const unsigned jobs = settings.jobs > 0 ? static_cast<unsigned>(settings.jobs) : hardware;
  track_in_batch(todo, prefixes, jobs, settings.quiet, [&](std::size_t i) {
    return track_file(todo[i].input, prefixes[i], settings, false).paragraph;
  });
}

const RegisterCommand track_registration{
    "track", "Track whole-body motion in C3D recordings with the S2KF", [](CLI::App& app) {
      auto settings = std::make_shared<TrackSettings>();
      app.add_option("recordings", settings->inputs, "C3D files or directories of them")->required();
      app.add_option("--out", settings->out,
                     "output folder (several recordings, or ending in / or an existing folder: outputs "
                     "mirror the input's subfolders), else the prefix of one recording (default: its name)");
      app.add_option("--height", settings->height_mm,
                     "subject height in mm (default: estimated from rigid marker pairs)")
          ->check(CLI::Range(300.0, 3000.0));
      app.add_option("--samples", settings->samples, "S2KF sample count (default 301)")
          ->check(CLI::Range(3, 100001));
      app.add_option("--preset", settings->preset, "noise preset: default or paper")
          ->check(CLI::IsMember({"default", "paper"}));
      app.add_option("--motion-model", settings->motion_model,
                     "S2KF system model: random-walk (default) or constant-velocity (docs/tracking.md)")
          ->check(CLI::IsMember({"random-walk", "constant-velocity"}));
      app.add_option("--method", settings->method, "s2kf, or baseline (per-frame Levenberg-Marquardt)")
          ->check(CLI::IsMember({"s2kf", "baseline"}));
      app.add_option("--markerset", settings->markerset,
                     "bundled marker set (kit, cmu, plugin_gait) or a .json file (default: the best match)");
      app.add_option("--subject", settings->subject, "calibrated subject file written by s2kf calibrate");
      app.add_flag("!--no-calibrate", settings->calibrate,
                   "track with the marker set as it is (default: calibrate marker offsets and bone lengths "
                   "on stretches of frames spread over the recording)");
      app.add_option("--calibration-frames", settings->calibration_frames,
                     "frames the calibration uses, in stretches spread over the recording (default 1200)")
          ->check(CLI::Range(10, 10000000));
      app.add_option("--calibration-shrink", settings->calibration_shrink,
                     "pull the marker offsets the recording sees only weakly towards the marker set: "
                     "a direction keeps mu / (mu + C) of the data's step (default 0.03; 0: none)")
          ->check(CLI::Range(0.0, 1e6));
      app.add_flag(
          "--smooth", settings->smooth,
          "offline Rauch-Tung-Striebel smoothing of the S2KF's motion (about 17 KB per frame in memory)");
      app.add_option("--figure", settings->figure_frame,
                     "draw frame F (0-based) as tracked: PREFIX_frameF.png/.svg, data and gnuplot script")
          ->check(CLI::NonNegativeNumber);
      app.add_option(
          "--truth", settings->truth,
          "ground-truth motion CSV (s2kf simulate's _truth.csv): adds the accuracy to the summary");
      app.add_flag("--realtime", settings->realtime,
                   "pace frames at the recording's rate and count deadline misses");
      app.add_flag("--html", settings->html,
                   "also write PREFIX.html: the motion in 3D in a browser (s2kf view)");
      app.add_flag("--quiet", settings->quiet, "print nothing but errors");
      add_output_options(app, settings->outputs);
      app.add_option("--jobs", settings->jobs, "recordings tracked at once (default: all cores)")
          ->check(CLI::Range(1, 1024));
      app.add_option("--shard", settings->shard,
                     "I/N: track only every N-th recording of the sorted list, from the I-th (0-based): "
                     "N runs with I = 0..N-1 track each recording once (Slurm job arrays, GNU parallel)");
      app.add_flag("--dry-run", settings->dry_run,
                   "print each recording this run would track and its output prefix; track nothing");
      app.add_flag("--verbose", settings->verbose, "also print the seconds each stage took");
      app.callback([settings] { run_track(*settings); });
    }};

}  // namespace
}  // namespace s2kf::cli
