// `s2kf track`: stream C3D recordings through the S2KF tracker and write the motion as CSV, OpenSim
// .mot, BVH, a JSON summary and a per-frame marker report. The work on one recording is in
// track_file.cpp; here are the options and the batch.
#include "calibrated_subject.hpp"
#include "command.hpp"
#include "extra_outputs.hpp"
#include "interruption.hpp"
#include "recording_batch.hpp"
#include "track_file.hpp"
#include "track_summary.hpp"
#include "tracker_samples.hpp"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace s2kf::cli {
namespace {

namespace fs = std::filesystem;

/// --static: the subject calibrated on the static trial in the model's zero pose (as `s2kf
/// calibrate STATIC --static` does), written to `path` as a subject file before any recording is
/// tracked with it.
void calibrate_on_static_trial(const TrackSettings& settings, const std::string& path) {
  const int samples = settings.samples > 0 ? settings.samples : track::TrackerOptions{}.samples;
  const CalibratedSubject calibrated =
      calibrate_subject_file(settings.static_trial, "--static",
                             static_trial_settings(settings.markerset, settings.height_mm,
                                                   settings.noise_from_calibration, settings.static_sd_deg),
                             cached_sample_set(46, samples), fs::path(path).stem().string());
  if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path());
  write_subject_file(path, subject_document(calibrated, settings.static_trial));
  if (settings.quiet) return;
  const calibration::SubjectCalibration& calibration = *calibrated.session.calibration;
  std::cout << fs::path(settings.static_trial).filename().string() << " (static trial): mean marker distance "
            << fixed_text(calibration.mean_marker_distance_before_mm, 1) << " mm with the marker set, "
            << fixed_text(calibration.mean_marker_distance_after_mm, 1)
            << " mm after calibrating in the zero pose; wrote " << path << "\n";
}

void run_track(const TrackSettings& given) {
  TrackSettings settings = given;
  if (!settings.markerset.empty() && !settings.subject.empty())
    throw UserError("give --markerset or --subject, not both (a subject file is a calibrated marker set)");
  if (!settings.static_trial.empty() && !settings.subject.empty())
    throw UserError(
        "give --static or --subject, not both (--static calibrates the subject on the static trial)");
  if (!settings.static_trial.empty() && !settings.calibrate)
    throw UserError(
        "--static calibrates the subject on the static trial; it cannot be combined with --no-calibrate");
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
  if (!settings.static_trial.empty()) {
    // One subject for every recording: PREFIX_subject.json beside one recording's outputs, else
    // STATIC-NAME_subject.json in the output folder. The recordings are then tracked with it as
    // with --subject (its marker set, no calibration on the recording).
    const std::string path = batch ? (fs::path(settings.out.empty() ? "." : settings.out) /
                                      (fs::path(settings.static_trial).stem().string() + "_subject.json"))
                                         .string()
                                   : prefixes[0] + "_subject.json";
    calibrate_on_static_trial(settings, path);
    settings.subject = path;
    settings.markerset.clear();
  }
  if (!batch) {
    if (fs::path(prefixes[0]).has_parent_path()) fs::create_directories(fs::path(prefixes[0]).parent_path());
    const bool terminal = isatty(STDERR_FILENO) && !settings.quiet;
    TrackSettings one = settings;  // one recording: its calibration may take every core
    one.calibration_threads = every_core();
    TrackOutcome outcome;
    try {
      outcome = track_file(todo[0].input, prefixes[0], one, terminal);
    } catch (...) {
      // The run wrote nothing of the recording's: the subject file --static wrote for it goes too.
      if (!settings.static_trial.empty()) fs::remove(settings.subject);
      throw;
    }
    if (!settings.quiet) std::cout << outcome.paragraph << "\n";
    return;
  }
  // A batch: one recording per thread. A recording that fails is reported (its line names it, its
  // PREFIX.json records why) and the others go on; the exit status says that some failed.
  const auto hardware = static_cast<unsigned>(every_core());
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
      app.add_option(
             "--gain", settings->gain,
             "S2KF update: information-form (default: the 46 x 46 state system and each body "
             "part's block of the innovation covariance) or square-root (the whole innovation "
             "covariance factorised; slower, docs/benchmarks.md) or information-form-root-products (the "
             "information form that also keeps the second order of the root's orientation the "
             "parts share; nearer the square-root update, slower than information-form)")
          ->check(CLI::IsMember({"information-form", "square-root", "information-form-root-products"}));
      app.add_option("--method", settings->method, "s2kf, or baseline (per-frame Levenberg-Marquardt)")
          ->check(CLI::IsMember({"s2kf", "baseline"}));
      app.add_option("--markerset", settings->markerset,
                     "bundled marker set (kit, cmu, plugin_gait) or a .json file (default: the best match)");
      app.add_option("--subject", settings->subject, "calibrated subject file written by s2kf calibrate");
      app.add_option("--static", settings->static_trial,
                     "C3D static trial of the same subject in the model's zero pose (standing upright, "
                     "arms hanging, every joint angle 0): calibrate the subject on it first (as s2kf "
                     "calibrate --static, written as PREFIX_subject.json) and track with it, which also "
                     "fixes the placement no moving recording shows (hands, forearms, feet)");
      app.add_option("--static-sd", settings->static_sd_deg,
                     "with --static: how far (SD, degrees) each joint may be from the zero pose (default 3)")
          ->check(CLI::Range(0.1, 90.0));
      app.add_flag("!--no-calibrate", settings->calibrate,
                   "track with the marker set as it is (default: calibrate marker offsets and bone lengths "
                   "on stretches of frames spread over the recording)");
      app.add_option("--calibration-frames", settings->calibration_frames,
                     "frames the calibration uses, in stretches spread over the recording (default 1200)")
          ->check(CLI::Range(10, 10000000));
      app.add_option("--calibration-samples", settings->calibration_samples,
                     "S2KF sample count of the calibration's tracking pass (default: --samples; fewer are "
                     "faster but move the calibration, docs/benchmarks.md)")
          ->check(CLI::Range(3, 100001));
      app.add_option("--calibration-shrink", settings->calibration_shrink,
                     "pull the marker offsets the recording sees only weakly towards the marker set: "
                     "a direction keeps mu / (mu + C) of the data's step (default 0.03; 0: none)")
          ->check(CLI::Range(0.0, 1e6));
      app.add_flag(
          "!--uniform-noise", settings->noise_from_calibration,
          "give every marker the same noise (default: after calibrating, each marker's noise follows its "
          "calibration residual, 0.5-2 times the common 10 mm)");
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
