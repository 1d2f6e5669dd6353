// `s2kf track`: stream C3D recordings through the S2KF tracker and write the motion as CSV, OpenSim
// .mot, BVH, a JSON summary and a per-frame marker report.
#include "calibration_hook.hpp"
#include "command.hpp"
#include "extra_outputs.hpp"
#include "frame_figure.hpp"
#include "marker_set_json.hpp"
#include "subject_height.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/io/bvh.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/io/motion_stream_writer.hpp>
#include <s2kf/track/gradient_baseline.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/tracking_run.hpp>
#include <s2kf/track/tracking_smoother.hpp>
#include <s2kf/track/truth_metrics.hpp>

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

namespace s2kf::cli {
namespace {

namespace fs = std::filesystem;

struct TrackSettings {
  std::vector<std::string> inputs;
  std::string out;
  double height_mm = 0;  // 0: estimate
  int samples = 0;       // 0: the preset's
  std::string preset = "default";
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
  OutputSettings outputs;  // --formats, --bvh-units, --derivatives (extra_outputs.hpp)
};

/// Memory the smoother may take before --smooth refuses a recording (it keeps every frame's
/// 46-state posterior, TrackingSmoother::kBytesPerFrame, about 17 KB).
constexpr double kSmoothingMemoryLimitBytes = 8e9;

/// Frames left out of the accuracy against the truth (spec/evaluation.md: the filter's start-up).
constexpr long kTruthWarmupFrames = 20;

/// Coordinates beyond a kilometre are not a body: the file's units or scale must be wrong.
constexpr double kAbsurdMm = 1e6;

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

std::vector<std::string> recording_labels(const c3d::C3dInfo& info) {
  std::vector<std::string> labels;
  for (const c3d::PointLabel& label : info.labels)
    labels.push_back(label.model_output ? std::string() : label.name);  // model outputs never match
  return labels;
}

TrackOutcome track_file(const std::string& input, const std::string& prefix, const TrackSettings& settings,
                        bool show_progress) {
  std::unique_ptr<c3d::C3dReader> reader;
  try {
    reader = std::make_unique<c3d::C3dReader>(input);
  } catch (const std::exception& e) {
    throw UserError(e.what());
  }
  const c3d::C3dInfo& info = reader->info();
  if (info.frame_count == 0) throw UserError(input + ": the recording holds no complete frame");
  if (!(info.rate > 0)) throw UserError(input + ": the recording has no valid frame rate");
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
  const MarkerSetChoice choice =
      choose_marker_set_for(recording_labels(info), settings.markerset, settings.subject);
  body::BodyModel model = choice.model;
  track::MarkerMapping mapping = choice.mapping;
  for (const c3d::PointLabel& label : info.labels)
    if (label.model_output) {
      auto& ignored = mapping.ignored_labels;
      std::replace(ignored.begin(), ignored.end(), std::string(), label.raw);
    }
  track::TrackerOptions options = track::preset_options(settings.preset, info.rate);
  if (settings.samples > 0) options.samples = settings.samples;
  apply_marker_noise(choice.set, options);
  if (mapping.markers_used() == 0)
    throw UserError(input + ": none of its " + std::to_string(info.point_count) +
                    " point labels is a marker of the marker set " + choice.set.name +
                    " (expected names such as LASI, RKNE, C7)");
  if (mapping.markers_used() < options.min_markers_to_start)
    throw UserError(input + ": only " + std::to_string(mapping.markers_used()) +
                    " of its labels are markers of the marker set " + choice.set.name + "; at least " +
                    std::to_string(options.min_markers_to_start) + " are needed to track");
  if (settings.smooth && static_cast<double>(info.frame_count) * track::TrackingSmoother::kBytesPerFrame >
                             kSmoothingMemoryLimitBytes)
    throw UserError(
        input + ": " + std::to_string(info.frame_count) + " frames are too many to smooth in memory (" +
        format(static_cast<double>(info.frame_count) * track::TrackingSmoother::kBytesPerFrame / 1e9, 1) +
        " GB); track without --smooth, or split the recording");

  if (settings.figure_frame >= info.frame_count)
    throw UserError(input + ": --figure " + std::to_string(settings.figure_frame) + " is beyond its " +
                    std::to_string(info.frame_count) + " frames (0-based)");
  std::vector<std::string> warnings = info.warnings;
  warnings.insert(warnings.end(), choice.warnings.begin(), choice.warnings.end());
  std::optional<SubjectHeight> found = subject_height(*reader, choice, settings.height_mm, input);
  if (!found) {
    found = SubjectHeight{1750, "default (no two markers on one segment to estimate it from)"};
    warnings.push_back("body height not estimable from the markers; 1750 mm assumed (use --height)");
  }
  const double height = found->mm;
  const std::string height_source = found->source;
  model = model.scaled(height);

  // Subject calibration: marker offsets and bone lengths fitted on the recording's first frames.
  nlohmann::json calibration_summary = nullptr;
  bool calibrate = settings.calibrate && settings.subject.empty();
  if (calibrate) {
    try {
      const track::SubjectCalibration calibration =
          calibrate_recording(*reader, model, choice, options, info.rate,
                              track::CalibrationOptions{}.iterations, settings.calibration_frames, false);
      model = calibration.model;
      calibration_summary = {
          {"frames", std::min<std::int64_t>(settings.calibration_frames, info.frame_count)},
          {"mean_marker_distance_before_mm", calibration.mean_marker_distance_before_mm},
          {"mean_marker_distance_after_mm", calibration.mean_marker_distance_after_mm},
          {"segment_scale", calibration.segment_scale}};
    } catch (const UserError& e) {
      // Too few usable frames to fit a subject: track with the marker set as it is, and say so.
      calibrate = false;
      warnings.push_back(std::string("subject not calibrated (") + e.what() +
                         "); the marker set is used as it is");
    }
  }

  std::unique_ptr<track::Tracker> s2kf_tracker;
  std::unique_ptr<track::GradientBaseline> baseline;
  std::unique_ptr<track::TrackingSmoother> smoother;
  if (settings.method == "s2kf") {
    s2kf_tracker = std::make_unique<track::Tracker>(model, mapping, options, info.rate);
    if (settings.smooth) smoother = std::make_unique<track::TrackingSmoother>(*s2kf_tracker);
  } else
    baseline = std::make_unique<track::GradientBaseline>(model, mapping);

  const auto start = std::chrono::steady_clock::now();
  const double frame_period = 1.0 / info.rate;
  long deadline_misses = 0;
  std::string bad_coordinates;
  c3d::Frame figure_points;  // the frame --figure draws, as recorded
  auto next_frame = [&](c3d::Frame& frame) {
    if (!bad_coordinates.empty() || !reader->read_frame(frame)) return false;
    for (Eigen::Index p = 0; p < frame.positions.cols(); ++p)
      if (frame.visible(p) && (frame.positions.col(p).cwiseAbs().maxCoeff() > kAbsurdMm)) {
        std::ostringstream s;
        s << input << ": frame " << frame.index << ", point " << info.labels[p].raw << " is at ("
          << frame.positions.col(p).transpose()
          << ") mm, beyond a kilometre: the file's units or scale are wrong";
        bad_coordinates = s.str();
        return false;
      }
    if (frame.index == settings.figure_frame) figure_points = frame;
    if (settings.realtime) {
      const auto due = start + std::chrono::duration<double>(static_cast<double>(frame.index) * frame_period);
      std::this_thread::sleep_until(due);
    }
    return true;
  };
  auto on_frame = [&](long index) {
    if (smoother) smoother->record(*s2kf_tracker, index);
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
  // Outputs, each written completely or not at all: without --smooth every row goes to the files as
  // it is tracked (memory stays constant however long the recording is); the smoother needs every
  // frame, so with --smooth the table is kept and written after smoothing.
  const std::string name = fs::path(input).stem().string();
  io::MotionStreamWriter motion_files(motion_file_paths(prefix, settings.outputs), model, info.rate, name,
                                      bvh_units(settings.outputs));
  write_model_outputs(motion_files, settings.outputs, prefix, input, model, mapping);  // .osim, .trc
  io::AtomicFileWriter marker_report(prefix + "_markers.csv");
  write_marker_report_header(marker_report.stream());
  std::optional<body::Pose> figure_pose;  // the pose of frame --figure, when it was tracked
  track::FrameSink sink;
  if (!smoother)
    sink = [&](const track::TrackedFrame& f) {
      motion_files.append(f.frame, f.time, f.values);
      write_marker_report_row(marker_report.stream(), f.frame, f.time, f.estimate.mean_marker_distance,
                              f.estimate.visible_markers);
      if (f.frame == settings.figure_frame && io::is_tracked_row(f.values)) {
        figure_pose.emplace();
        figure_pose->root_position = f.values.head<3>();
        figure_pose->root_rpy = f.values.segment<3>(3);
        figure_pose->joints = f.values.tail(f.values.size() - 6);
      }
    };
  const auto joint_names = model.joint_names();
  track::TrackingRun run =
      s2kf_tracker
          ? track::run_tracking(*s2kf_tracker, next_frame, info.rate, joint_names, false, on_frame, sink)
          : track::run_tracking(*baseline, next_frame, info.rate, joint_names, false, on_frame, sink);
  if (show_progress) std::cerr << "\n";
  if (!bad_coordinates.empty()) throw UserError(bad_coordinates);
  if (run.frames_tracked == 0)
    throw UserError(input + ": no frame has the " + std::to_string(options.min_markers_to_start) +
                    " visible markers needed to start tracking");
  warnings.insert(warnings.end(), run.warnings.begin(), run.warnings.end());
  if (smoother) {
    smoother->smooth(run.motion);
    for (Eigen::Index r = 0; r < run.motion.frames(); ++r) {
      const auto f = static_cast<std::size_t>(r);
      motion_files.append(run.motion.frame[f], run.motion.time[f], run.motion.values.row(r).transpose());
      write_marker_report_row(marker_report.stream(), run.motion.frame[f], run.motion.time[f],
                              run.mean_marker_distance[f], run.visible_markers[f]);
      if (run.motion.frame[f] == settings.figure_frame &&
          io::is_tracked_row(run.motion.values.row(r).transpose()))
        figure_pose = track::pose_of_row(run.motion, r);
    }
  }
  std::string figure_file;
  if (settings.figure_frame >= 0) {
    std::string problem;
    if (!figure_pose)
      warnings.push_back("frame " + std::to_string(settings.figure_frame) +
                         " was not tracked: no figure drawn");
    else if (draw_tracked_frame(prefix, settings.figure_frame, model, mapping, *figure_pose,
                                figure_points.positions, figure_points.visible, problem))
      figure_file = prefix + "_frame" + std::to_string(settings.figure_frame) + ".png";
    else
      warnings.push_back(problem);
  }

  const long converged = track::converged_frame(run.mean_marker_distance);
  const double level = track::mean_from(run.mean_marker_distance, converged);
  // The convergence rule (spec/evaluation.md) restarts at any late frame above 1.5 times the final
  // level, so on long real recordings the mean over every tracked frame is reported as well.
  const double overall = track::mean_from(run.mean_marker_distance, 0);
  if (calibrate) {
    // The calibration's distance with the calibrated subject, from this run: the tracker is causal,
    // so its first frames are what a final calibration pass would track (s2kf calibrate's "after").
    const auto& distance = run.mean_marker_distance;
    const std::size_t end =
        std::min<std::size_t>(distance.size(), static_cast<std::size_t>(settings.calibration_frames));
    std::size_t first = 0;
    while (first < end && !std::isfinite(distance[first])) ++first;
    const std::size_t from =
        std::min<std::size_t>(end, first + static_cast<std::size_t>(track::CalibrationOptions{}.skip_frames));
    const double after =
        track::mean_from(std::vector<double>(distance.begin() + static_cast<std::ptrdiff_t>(from),
                                             distance.begin() + static_cast<std::ptrdiff_t>(end)),
                         0);
    calibration_summary["mean_marker_distance_after_mm"] =
        std::isfinite(after) ? nlohmann::json(after) : nlohmann::json(nullptr);
  }
  std::vector<double>& latency_ms = run.seconds;  // not needed in seconds any more
  for (double& s : latency_ms) s *= 1000;
  const double median_ms = track::quantile(latency_ms, 0.5), p99_ms = track::quantile(latency_ms, 0.99);

  motion_files.finish();
  marker_report.commit();
  // Accuracy against the truth, from the motion as written (frames from the 20th on).
  nlohmann::json truth_summary = nullptr;
  std::optional<track::TruthComparison> accuracy;
  if (truth) {
    try {
      accuracy =
          track::compare_with_truth(model, io::load_motion_csv(prefix + ".csv"), *truth, kTruthWarmupFrames);
    } catch (const std::invalid_argument& e) {
      throw UserError("--truth: " + settings.truth + ": " + e.what());
    }
    truth_summary = {{"frames_compared", accuracy->frames},
                     {"warmup_frames", kTruthWarmupFrames},
                     {"all_joint_rms_deg", accuracy->all_joint_rms_deg},
                     {"segment_orientation_rms_deg", accuracy->segment_orientation_rms_deg},
                     {"limb_flexion_rms_deg", accuracy->limb_flexion_rms_deg},
                     {"root_position_rms_mm", accuracy->root_position_rms_mm},
                     {"root_orientation_rms_deg", accuracy->root_orientation_rms_deg},
                     {"worst_joint", accuracy->worst_joint},
                     {"worst_joint_rms_deg", accuracy->worst_joint_rms_deg},
                     {"joint_limit_violations", accuracy->joint_limit_violations}};
  }
  std::vector<std::string> markers_used;
  for (int m = 0; m < model.marker_count(); ++m)
    if (mapping.point_of_marker[m] >= 0) markers_used.push_back(model.markers[m].name);
  nlohmann::json summary = {
      {"input", input},
      {"method", settings.method},
      {"marker_set", choice.set.name},
      {"marker_set_source", choice.source},
      {"marker_set_messages", choice.messages},
      {"calibration", calibration_summary},
      {"smoothed", smoother != nullptr},
      {"preset", options.preset},
      {"frames", run.frames},
      {"frames_tracked", run.frames_tracked},
      {"rate", info.rate},
      {"height_mm", height},
      {"height_source", height_source},
      {"markers_used", markers_used},
      {"labels_ignored", mapping.ignored_labels},
      {"mean_marker_distance_mm", std::isfinite(level) ? nlohmann::json(level) : nlohmann::json(nullptr)},
      {"converged_frame", converged},
      {"mean_marker_distance_all_frames_mm",
       std::isfinite(overall) ? nlohmann::json(overall) : nlohmann::json(nullptr)},
      {"latency_ms", {{"median", median_ms}, {"p99", p99_ms}}},
      {"samples", settings.method == "s2kf" ? nlohmann::json(options.samples) : nlohmann::json(nullptr)},
      {"warnings", warnings},
  };
  if (settings.realtime) summary["deadline_misses"] = deadline_misses;
  if (truth) summary["truth"] = truth_summary;
  io::write_file_atomically(prefix + ".json", [&](std::ostream& out) { out << summary.dump(2) << "\n"; });

  std::ostringstream paragraph;
  for (const std::string& message : choice.messages) paragraph << message << "\n";
  paragraph << name << ": tracked " << run.frames_tracked << " of " << run.frames << " frames at "
            << format(info.rate, 0) << " Hz with " << markers_used.size() << " markers ("
            << mapping.ignored_labels.size() << " labels ignored), body height " << format(height, 0)
            << " mm (" << height_source << "), marker set " << choice.set.name;
  const auto millimetres = [](const nlohmann::json& value) {
    return value.is_number() && std::isfinite(value.get<double>()) ? format(value.get<double>(), 1)
                                                                   : std::string("n/a");
  };
  if (calibrate)
    paragraph << ", calibrated on " << calibration_summary["frames"].get<std::int64_t>() << " frames ("
              << millimetres(calibration_summary["mean_marker_distance_before_mm"]) << " -> "
              << millimetres(calibration_summary["mean_marker_distance_after_mm"]) << " mm)";
  if (std::isfinite(level))
    paragraph << ". Converged at frame " << converged << "; mean marker distance after that "
              << format(level, 1) << " mm (" << format(overall, 1) << " mm over all tracked frames)";
  else
    paragraph << ". The marker distance never settled within 1.5 times its final level; mean "
              << format(overall, 1) << " mm over all tracked frames";
  paragraph << ". Latency per frame: median " << format(median_ms, 3) << " ms, p99 " << format(p99_ms, 3)
            << " ms";
  if (settings.method == "s2kf") paragraph << " (" << options.samples << " samples)";
  paragraph << ".";
  if (smoother) paragraph << " Motion smoothed (RTS); marker distances are the filter's.";
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
  if (!figure_file.empty()) paragraph << ", and the figure " << figure_file;
  paragraph << ".";
  return {summary, paragraph.str()};
}

/// Expands directories into their .c3d files (sorted), keeps files as given.
std::vector<std::string> expand_inputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> files;
  for (const std::string& input : inputs) {
    if (fs::is_directory(input)) {
      std::vector<std::string> found;
      for (const auto& entry : fs::directory_iterator(input)) {
        std::string ext = entry.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
        if (entry.is_regular_file() && ext == ".c3d") found.push_back(entry.path().string());
      }
      if (found.empty()) throw UserError(input + " is a directory without .c3d files");
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else if (!fs::exists(input)) {
      throw UserError(input + ": no such file");
    } else {
      files.push_back(input);
    }
  }
  return files;
}

void run_track(const TrackSettings& settings) {
  if (!settings.markerset.empty() && !settings.subject.empty())
    throw UserError("give --markerset or --subject, not both (a subject file is a calibrated marker set)");
  if (settings.smooth && settings.method != "s2kf")
    throw UserError("--smooth works on the S2KF's estimates; it cannot be combined with --method baseline");
  const std::vector<std::string> files = expand_inputs(settings.inputs);
  const bool batch = files.size() > 1;
  if (batch && !settings.truth.empty())
    throw UserError("--truth belongs to one recording; track that recording on its own");
  const bool terminal = isatty(STDERR_FILENO) && !settings.quiet;
  check_outputs(settings.outputs, output_prefixes(files, settings.out), !settings.truth.empty());
  if (!batch) {
    const std::string prefix = settings.out.empty() ? fs::path(files[0]).stem().string() : settings.out;
    if (fs::path(prefix).has_parent_path()) fs::create_directories(fs::path(prefix).parent_path());
    const TrackOutcome outcome = track_file(files[0], prefix, settings, terminal);
    if (!settings.quiet) std::cout << outcome.paragraph << "\n";
    return;
  }
  // Many recordings: one per thread, outputs in the --out directory named after each recording.
  const fs::path directory = settings.out.empty() ? fs::path(".") : fs::path(settings.out);
  fs::create_directories(directory);
  const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  const unsigned jobs = settings.jobs > 0 ? static_cast<unsigned>(settings.jobs) : hardware;
  std::atomic<std::size_t> next{0};
  std::mutex print;
  std::vector<std::string> failures;
  auto worker = [&]() {
    for (std::size_t i; (i = next++) < files.size();) {
      const std::string prefix = (directory / fs::path(files[i]).stem()).string();
      try {
        const TrackOutcome outcome = track_file(files[i], prefix, settings, false);
        std::lock_guard<std::mutex> lock(print);
        if (!settings.quiet) std::cout << outcome.paragraph << "\n\n";
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(print);
        failures.push_back(e.what());
        std::cerr << "s2kf: " << e.what() << "\n";
      }
    }
  };
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < std::min<std::size_t>(jobs, files.size()); ++t) threads.emplace_back(worker);
  for (auto& thread : threads) thread.join();
  if (!failures.empty())
    throw UserError(std::to_string(failures.size()) + " of " + std::to_string(files.size()) +
                    " recordings could not be tracked (see above)");
}

const RegisterCommand track_registration{
    "track", "Track whole-body motion in C3D recordings with the S2KF", [](CLI::App& app) {
      auto settings = std::make_shared<TrackSettings>();
      app.add_option("recordings", settings->inputs, "C3D files or directories of them")->required();
      app.add_option("--out", settings->out,
                     "output prefix (one recording; default: its name) or directory (several)");
      app.add_option("--height", settings->height_mm,
                     "subject height in mm (default: estimated from rigid marker pairs)")
          ->check(CLI::Range(300.0, 3000.0));
      app.add_option("--samples", settings->samples, "S2KF sample count (default 301)")
          ->check(CLI::Range(3, 100001));
      app.add_option("--preset", settings->preset, "noise preset: default or paper")
          ->check(CLI::IsMember({"default", "paper"}));
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
      app.add_flag("--quiet", settings->quiet, "print nothing but errors");
      add_output_options(app, settings->outputs);
      app.add_option("--jobs", settings->jobs, "recordings tracked at once (default: all cores)")
          ->check(CLI::Range(1, 1024));
      app.callback([settings] { run_track(*settings); });
    }};

}  // namespace
}  // namespace s2kf::cli
