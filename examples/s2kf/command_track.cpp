// `s2kf track`: stream C3D recordings through the S2KF tracker and write the motion as CSV, OpenSim
// .mot, BVH, a JSON summary and a per-frame marker report.
#include "command.hpp"
#include "extra_outputs.hpp"
#include "frame_figure.hpp"
#include "inferred_marker_set.hpp"
#include "interruption.hpp"
#include "marker_set_json.hpp"
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

std::string format(double value, int precision = 1) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << value;
  return s.str();
}

/// The per-frame marker report PREFIX_markers.csv: its header, and one line per frame.
void write_marker_report_header(std::ostream& out) {
  out << "frame,time,mean_marker_distance_mm,visible_markers\n";
}
void write_marker_report_row(std::ostream& out, long frame, double time, double mean_marker_distance,
                             int visible_markers) {
  out << std::setprecision(9) << frame << "," << time << ",";
  if (std::isfinite(mean_marker_distance))
    out << mean_marker_distance;
  else
    out << "nan";
  out << "," << visible_markers << "\n";
}

/// The per-frame segment report PREFIX_segments.csv: per segment, the filter's largest standard
/// deviation of its angles this frame (deg, segment_uncertainty_deg; "nan" where the frame was not
/// filtered, e.g. rows replayed after smoothing).
void write_segment_report_header(std::ostream& out, const track::SegmentObservation& segments) {
  out << "frame,time";
  for (const std::string& segment : segments.segments) out << "," << segment << "_sd_deg";
  out << "\n";
}
void write_segment_report_row(std::ostream& out, const track::Session& session,
                              const track::TrackedFrame& f) {
  Eigen::VectorXd sd = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(session.segments.segments.size()),
                                                 std::numeric_limits<double>::quiet_NaN());
  if (f.estimate && f.estimate->tracked)
    sd = track::segment_uncertainty_deg(session.model, session.segments, f.estimate->pose.joints,
                                        f.estimate->covariance);
  out << std::setprecision(6) << f.frame << "," << f.time;
  for (Eigen::Index s = 0; s < sd.size(); ++s) {
    if (std::isfinite(sd(s)))
      out << "," << sd(s);
    else
      out << ",nan";
  }
  out << "\n";
}

/// The accuracy against a simulated recording's truth, as the summary's "truth" object.
nlohmann::json truth_json(const track::TruthComparison& accuracy) {
  return {{"frames_compared", accuracy.frames},
          {"warmup_frames", kTruthWarmupFrames},
          {"all_joint_rms_deg", accuracy.all_joint_rms_deg},
          {"segment_orientation_rms_deg", accuracy.segment_orientation_rms_deg},
          {"limb_flexion_rms_deg", accuracy.limb_flexion_rms_deg},
          {"root_position_rms_mm", accuracy.root_position_rms_mm},
          {"root_orientation_rms_deg", accuracy.root_orientation_rms_deg},
          {"worst_joint", accuracy.worst_joint},
          {"worst_joint_rms_deg", accuracy.worst_joint_rms_deg},
          {"joint_limit_violations", accuracy.joint_limit_violations}};
}

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
                    " frames are too many to smooth in memory (" + format(smoothing_bytes / 1e9, 1) +
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
    write_marker_report_row(marker_report, f.frame, f.time, f.mean_marker_distance, f.visible_markers);
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
                                         settings.smooth, warnings, outside);
  if (settings.realtime) summary["deadline_misses"] = deadline_misses;
  if (accuracy) summary["truth"] = truth_json(*accuracy);
  // Labels and file names are UTF-8 (the reader decodes Latin-1); anything else is replaced, never
  // a reason to lose the run.
  motion_files.companion(prefix + ".json")
      << summary.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  throw_if_interrupted();
  motion_files.finish();
  if (settings.html)
    viewer::write_result_page(prefix, session.model, session.mapping, settings.truth);  // --html

  const long converged = summary["converged_frame"].get<long>();
  const double level = summary_number(summary["mean_marker_distance_mm"]);
  const double overall = summary_number(summary["mean_marker_distance_all_frames_mm"]);
  const double median_ms = summary["latency_ms"]["median"].get<double>();
  const double p99_ms = summary["latency_ms"]["p99"].get<double>();
  const nlohmann::json& calibration_summary = summary["calibration"];
  std::ostringstream paragraph;
  for (const std::string& message : messages) paragraph << message << "\n";
  paragraph << name << ": tracked " << run.frames_tracked << " of " << run.frames << " frames at "
            << format(info.rate, 0) << " Hz with " << summary["markers_used"].size() << " markers ("
            << session.mapping.ignored_labels.size() << " labels ignored), body height "
            << format(session.height_mm, 0) << " mm (" << session.height_source << "), marker set "
            << choice.set.name;
  const auto millimetres = [](const nlohmann::json& value) {
    return value.is_number() && std::isfinite(value.get<double>()) ? format(value.get<double>(), 1)
                                                                   : std::string("n/a");
  };
  if (session.calibration)
    paragraph << ", calibrated on " << session.calibration_frames << " frames ("
              << millimetres(calibration_summary["mean_marker_distance_before_mm"]) << " -> "
              << millimetres(calibration_summary["mean_marker_distance_after_mm"]) << " mm)";
  if (std::isfinite(level))
    paragraph << ". Converged at frame " << converged << "; mean marker distance after that "
              << format(level, 1) << " mm (" << format(overall, 1) << " mm over all tracked frames)";
  else
    paragraph << ". The marker distance never settled (its median over a second stayed above 1.5 times its "
                 "median over the recording); mean "
              << format(overall, 1) << " mm over all tracked frames";
  paragraph << ". Latency per frame: median " << format(median_ms, 3) << " ms, p99 " << format(p99_ms, 3)
            << " ms";
  if (settings.method == "s2kf") paragraph << " (" << session.tracker.samples << " samples)";
  paragraph << ".";
  if (settings.smooth) paragraph << " Motion smoothed (RTS); marker distances are the filter's.";
  if (settings.realtime) paragraph << " Real-time pacing: " << deadline_misses << " deadline misses.";
  if (accuracy)
    paragraph << " Against the truth (frames " << kTruthWarmupFrames << " on): all-joint RMS "
              << format(accuracy->all_joint_rms_deg, 2) << " deg, segment orientation "
              << format(accuracy->segment_orientation_rms_deg, 2) << " deg, limb flexion "
              << format(accuracy->limb_flexion_rms_deg, 2) << " deg, root position "
              << format(accuracy->root_position_rms_mm, 1) << " mm.";
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
      paragraph << " " << stage << " " << format(seconds, 3) << (stage == "writing" ? "" : ",");
    paragraph << " (" << format(times.sum(), 3) << " in all).";
  }
  return {summary, paragraph.str()};
}

/// A recording to track and the name of its outputs: its path below the folder it was found in,
/// without the extension ("S01/Walk01"), or its file name for a file given as such.
struct Recording {
  std::string input;
  std::string name;
};

bool is_c3d_file(const fs::directory_entry& entry) {
  std::string ext = entry.path().extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".c3d" && entry.is_regular_file();
}

/// The recordings of the command line: every .c3d file in a folder, at any depth, named by its path
/// below that folder (so outputs mirror the folders and same-named takes of different subjects
/// stay apart), and every file given as such, named after itself. Sorted by name: the order
/// --shard deals out, the same on every machine wherever the data are mounted.
std::vector<Recording> find_recordings(const std::vector<std::string>& inputs) {
  std::vector<Recording> recordings;
  for (const std::string& input : inputs) {
    if (fs::is_directory(input)) {
      std::size_t found = 0;
      for (const auto& entry :
           fs::recursive_directory_iterator(input, fs::directory_options::skip_permission_denied))
        if (is_c3d_file(entry)) {
          recordings.push_back({entry.path().string(),
                                entry.path().lexically_relative(input).replace_extension().generic_string()});
          ++found;
        }
      if (found == 0)
        throw UserError(input + " is a folder without .c3d files (its subfolders searched too)");
    } else if (!fs::exists(input)) {
      throw UserError(input + ": no such file");
    } else {
      recordings.push_back({input, fs::path(input).stem().string()});
    }
  }
  std::sort(recordings.begin(), recordings.end(), [](const Recording& a, const Recording& b) {
    return std::tie(a.name, a.input) < std::tie(b.name, b.input);
  });
  return recordings;
}

/// --shard I/N: the recordings whose place in the sorted list is I modulo N (I from 0 to N-1), so N
/// runs with I = 0..N-1 track every recording exactly once, in parts that differ by one at most.
std::vector<Recording> shard_of(const std::vector<Recording>& recordings, const std::string& shard) {
  const auto slash = shard.find('/');
  const auto whole_number = [](const std::string& text) {
    return !text.empty() && text.size() <= 9 && text.find_first_not_of("0123456789") == std::string::npos;
  };
  if (slash == std::string::npos || !whole_number(shard.substr(0, slash)) ||
      !whole_number(shard.substr(slash + 1)))
    throw UserError("--shard " + shard + ": expected I/N with whole numbers 0 <= I < N, e.g. --shard 0/8");
  const std::size_t index = std::stoul(shard.substr(0, slash)), count = std::stoul(shard.substr(slash + 1));
  if (count == 0 || index >= count)
    throw UserError("--shard " + shard + ": I counts from 0 and must be smaller than N (the shards of N = " +
                    std::to_string(count) + " are 0/" + std::to_string(count) + " to " +
                    std::to_string(count == 0 ? 0 : count - 1) + "/" + std::to_string(count) + ")");
  std::vector<Recording> part;
  for (std::size_t k = index; k < recordings.size(); k += count) part.push_back(recordings[k]);
  return part;
}

/// An error of one recording in a batch as one line that starts with the recording's path.
std::string error_naming_file(const std::string& input, const std::exception& error) {
  if (const auto* c3d_error = dynamic_cast<const c3d::C3dError*>(&error))
    return input + ": " + c3d_error->sentence();
  const std::string what = error.what();
  return what.rfind(input, 0) == 0 ? what : input + ": " + what;
}

/// In place of the summary of a recording that failed in a batch: PREFIX.json with its error, which
/// s2kf summarize lists. Outputs an earlier run left under the prefix stay as they were.
void record_failure(const std::string& input, const std::string& prefix, const std::string& error) {
  const nlohmann::json record = {{"input", input}, {"status", "failed"}, {"error", error}};
  io::write_file_atomically(prefix + ".json", [&](std::ostream& out) { out << record.dump(2) << "\n"; });
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
  std::vector<std::string> prefixes;
  for (const Recording& recording : todo)
    prefixes.push_back(out_is_folder
                           ? (fs::path(settings.out.empty() ? "." : settings.out) / recording.name).string()
                       : settings.out.empty() ? recording.name
                                              : settings.out);
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
    const TrackOutcome outcome = track_file(todo[0].input, prefixes[0], settings, terminal);
    if (!settings.quiet) std::cout << outcome.paragraph << "\n";
    return;
  }
  // A batch: one recording per thread. A recording that fails is reported (its line names it, its
  // PREFIX.json records why) and the others go on; the exit status says that some failed.
  const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  const unsigned jobs = settings.jobs > 0 ? static_cast<unsigned>(settings.jobs) : hardware;
  // Largest files first: a long recording started last would leave the other threads idle at the
  // end. (Were times proportional to sizes, longest-first would stay within 4/3 of the best order.)
  std::vector<std::uintmax_t> bytes;
  for (const Recording& recording : todo) {
    std::error_code error;
    const std::uintmax_t size = fs::file_size(recording.input, error);
    bytes.push_back(error ? 0 : size);
  }
  std::vector<std::size_t> order(todo.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return bytes[a] > bytes[b]; });
  std::atomic<std::size_t> next{0};
  std::mutex print;
  std::vector<std::string> failures;
  auto worker = [&]() {
    for (std::size_t n; (n = next++) < todo.size();) {
      const std::size_t i = order[n];
      const std::string& input = todo[i].input;
      try {
        fs::create_directories(fs::path(prefixes[i]).parent_path());
        const TrackOutcome outcome = track_file(input, prefixes[i], settings, false);
        std::lock_guard<std::mutex> lock(print);
        if (!settings.quiet) std::cout << outcome.paragraph << "\n\n" << std::flush;
      } catch (const std::exception& e) {
        const std::string message = error_naming_file(input, e);
        std::string unrecorded;
        try {
          record_failure(input, prefixes[i], message);
        } catch (const std::exception& f) {
          unrecorded = error_naming_file(input, f);
        }
        std::lock_guard<std::mutex> lock(print);
        failures.push_back(input);
        std::cerr << "s2kf: " << message << "\n";
        if (!unrecorded.empty()) std::cerr << "s2kf: " << unrecorded << "\n";
      }
    }
  };
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < std::min<std::size_t>(jobs, todo.size()); ++t) threads.emplace_back(worker);
  for (auto& thread : threads) thread.join();
  if (failures.empty()) return;
  std::sort(failures.begin(), failures.end());
  constexpr std::size_t kNamed = 10;  // a failure list longer than this ends in "and N more"
  std::string list;
  for (std::size_t i = 0; i < std::min(kNamed, failures.size()); ++i) list += (i ? ", " : "") + failures[i];
  if (failures.size() > kNamed) list += " and " + std::to_string(failures.size() - kNamed) + " more";
  throw UserError(std::to_string(failures.size()) + " of " + std::to_string(todo.size()) +
                  " recordings could not be tracked: " + list +
                  " (errors above and in each one's .json; the others were tracked)");
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
                   "on the recording's first frames)");
      app.add_option("--calibration-frames", settings->calibration_frames,
                     "frames from the start the calibration uses (default 1200)")
          ->check(CLI::Range(10, 10000000));
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
