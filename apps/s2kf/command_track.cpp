// `s2kf track`: stream C3D recordings through the S2KF tracker and write the motion as CSV, OpenSim
// .mot, BVH, a JSON summary and a per-frame marker report. The work on one recording is in
// track_file.cpp; here are the options and the batch.
#include <s2kf/app/calibrated_subject.hpp>
#include <s2kf/app/extra_outputs.hpp>
#include <s2kf/app/sample_sets.hpp>
#include <s2kf/app/track_summary.hpp>
#include "command.hpp"
#include "interruption.hpp"
#include "output_options.hpp"
#include "recording_batch.hpp"
#include "track_file.hpp"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace s2kf::cli {
namespace {

namespace fs = std::filesystem;

/// --static: the subject calibrated on the static trial in its reference pose (as `s2kf calibrate
/// STATIC --static` does), written to `path` as a subject file before any recording is
/// tracked with it. Markers the set does not name are placed by the motion of `recording` (the
/// first tracked), their set written to `completed_path`, and calibrated with the others.
std::optional<MarkerSetChoice> calibrate_on_static_trial(const TrackSettings& settings,
                                                         const std::string& path,
                                                         const std::string& recording,
                                                         const std::string& completed_path) {
  const app::TrackRequest& request = settings.request;
  const std::optional<MarkerSetChoice> completed =
      fs::is_regular_file(recording) ? app::completed_set_for_static_trial(request, recording, completed_path)
                                     : std::nullopt;
  if (completed && !settings.quiet) std::cout << recording << ": marker set " << completed->source << "\n";
  app::StaticTrialPlacedMarkers placed;
  const CalibratedSubject calibrated = app::calibrate_static_trial(
      request, cached_sample_set(46, request.samples), fs::path(path).stem().string(),
      completed ? &*completed : nullptr, recording, &placed);
  if (!placed.left_out.empty() && !settings.quiet) std::cout << recording << ": " << placed.left_out << "\n";
  if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path());
  write_subject_file(path, subject_document(calibrated, request.static_trial));
  if (settings.quiet) return completed;
  const calibration::SubjectCalibration& calibration = *calibrated.session.calibration;
  std::cout << fs::path(request.static_trial).filename().string() << " (static trial): mean marker distance "
            << fixed_text(calibration.mean_marker_distance_before_mm, 1) << " mm with the marker set, "
            << fixed_text(calibration.mean_marker_distance_after_mm, 1) << " mm after calibrating in the "
            << static_posture_text(calibrated, app::static_trial_settings(request)) << "; wrote " << path
            << "\n";
  return completed;
}

void run_track(const TrackSettings& given) {
  TrackSettings settings = given;
  app::TrackRequest& request = settings.request;
  check_request(request);  // before any file is looked at
  if (const std::string deprecated = app::deprecation_warning(request); !deprecated.empty())
    std::cerr << "s2kf: warning: " << deprecated << "\n";
  const std::vector<Recording> recordings = find_recordings(settings.inputs);
  const bool batch = recordings.size() > 1 || !settings.shard.empty() ||
                     std::any_of(settings.inputs.begin(), settings.inputs.end(),
                                 [](const std::string& input) { return fs::is_directory(input); });
  if (recordings.size() > 1 && !request.truth.empty())
    throw UserError("--truth belongs to one recording; track that recording on its own");
  const std::vector<Recording> todo =
      settings.shard.empty() ? recordings : shard_of(recordings, settings.shard);
  // --out is a folder for a batch, and for one recording when it is one or ends in '/'; else the
  // prefix of the one recording's files.
  const bool out_is_folder =
      batch || (!settings.out.empty() && (settings.out.back() == '/' || fs::is_directory(settings.out)));
  const std::vector<std::string> prefixes = output_prefixes(todo, settings.out, out_is_folder);
  check_outputs(settings.outputs, prefixes, !request.truth.empty());
  if (settings.dry_run || todo.empty()) {
    if (todo.empty() && !settings.quiet)
      std::cout << "shard " << settings.shard << " holds none of the " << recordings.size()
                << " recordings\n";
    for (std::size_t i = 0; i < todo.size(); ++i) std::cout << todo[i].input << " -> " << prefixes[i] << "\n";
    return;
  }
  // --static: each recording is calibrated together with the static trial (app::prepare_track),
  // its subject written as PREFIX_subject.json (track_file); --static-alone calibrates here first.
  const std::string static_trial = request.static_alone ? request.static_trial : std::string();
  if (!static_trial.empty()) {
    // One subject for every recording: PREFIX_subject.json beside one recording's outputs, else
    // STATIC-NAME_subject.json in the output folder. The recordings are then tracked with it as
    // with --subject (its marker set, no calibration on the recording).
    const std::string path = batch ? (fs::path(settings.out.empty() ? "." : settings.out) /
                                      (fs::path(static_trial).stem().string() + "_subject.json"))
                                         .string()
                                   : prefixes[0] + "_subject.json";
    std::optional<MarkerSetChoice> placed =
        calibrate_on_static_trial(settings, path, todo[0].input, prefixes[0] + "_markerset.json");
    request.subject = path;
    request.markerset.clear();
    settings.placed_for_static = std::move(placed);  // listed in each summary
    request.static_trial.clear();
    request.static_alone = false;
  }
  if (!batch) {
    if (fs::path(prefixes[0]).has_parent_path()) fs::create_directories(fs::path(prefixes[0]).parent_path());
    const bool terminal = isatty(STDERR_FILENO) && !settings.quiet;
    TrackOutcome outcome;
    try {
      outcome = track_file(todo[0].input, prefixes[0], settings, terminal);  // every core calibrates
    } catch (...) {
      // The run wrote nothing of the recording's: the subject file --static wrote for it goes too.
      if (!static_trial.empty()) fs::remove(request.subject.empty() ? request.markerset : request.subject);
      throw;
    }
    if (!settings.quiet) std::cout << outcome.paragraph << "\n";
    return;
  }
  // A batch: one recording per thread. A recording that fails is reported (its line names it, its
  // PREFIX.json records why) and the others go on; the exit status says that some failed.
  request.calibration_threads = 1;  // the recordings share the cores
  const auto hardware = static_cast<unsigned>(every_core());
  const unsigned jobs = settings.jobs > 0 ? static_cast<unsigned>(settings.jobs) : hardware;
  track_in_batch(todo, prefixes, jobs, settings.quiet, [&](std::size_t i) {
    return track_file(todo[i].input, prefixes[i], settings, false).paragraph;
  });
}

const RegisterCommand track_registration{
    "track", "Track whole-body motion in C3D recordings with the S2KF", [](CLI::App& app) {
      auto settings = std::make_shared<TrackSettings>();
      app.option_defaults()->always_capture_default();  // --help shows each default (Python's too)
      app.add_option("recordings", settings->inputs, "C3D files or directories of them")->required();
      app.add_option("--out", settings->out,
                     "output folder (several recordings, or ending in / or an existing folder: outputs "
                     "mirror the input's subfolders), else the prefix of one recording (default: its name)");
      app.add_option("--height", settings->request.height_mm,
                     "subject height in mm (default: estimated from rigid marker pairs)")
          ->check(CLI::Range(300.0, 3000.0));
      app.add_option("--samples", settings->request.samples, "S2KF sample count")
          ->check(CLI::Range(3, 100001));
      app.add_option("--preset", settings->request.preset, "noise preset: default or paper")
          ->check(CLI::IsMember({"default", "paper"}));
      app.add_option("--motion-model", settings->request.motion_model,
                     "S2KF system model: random-walk or constant-velocity (docs/tracking.md)")
          ->check(CLI::IsMember({"random-walk", "constant-velocity"}));
      // No CLI11 check: a removed gain gets app::check_request's sentence naming its replacement.
      app.add_option("--gain", settings->request.gain,
                     "S2KF update: information-form (the default: the 46 x 46 state system and each body "
                     "part's block of the innovation covariance; the most accurate on the simulated limbs "
                     "and 9 % faster) or square-root (the exact update: the whole innovation covariance "
                     "factorised; the better one on occluded segments and on the real recordings' marker "
                     "distances, docs/tracking.md)");
      app.add_option("--method", settings->request.method,
                     "s2kf, or baseline (per-frame Levenberg-Marquardt)")
          ->check(CLI::IsMember({"s2kf", "baseline"}));
      app.add_option("--markerset", settings->request.markerset,
                     "bundled marker set (kit, cmu, plugin_gait) or a .json file (default: the best match)");
      app.add_option("--subject", settings->request.subject,
                     "calibrated subject file written by s2kf calibrate");
      app.add_option("--static", settings->request.static_trial,
                     "C3D static trial of the same subject standing still in a reference pose "
                     "(--static-pose): calibrate the subject on it and each recording together, in one "
                     "bundle adjustment (the static trial fixes the placement no moving recording shows: "
                     "hands, forearms, feet; the recording's bending joints the rest), written as "
                     "PREFIX_subject.json");
      app.add_flag("--static-alone", settings->request.static_alone,
                   "with --static: calibrate the subject on the static trial alone (as s2kf calibrate "
                   "--static), write it as PREFIX_subject.json (a batch: STATIC_subject.json) and track "
                   "every recording with it as with --subject");  // without --static: app::check_request
      app.add_option("--static-sd", settings->request.static_sd_deg,
                     "with --static or a static stretch: how far (SD, degrees) each joint may be from the "
                     "reference pose")
          ->check(CLI::Range(0.1, 90.0));
      app.add_option("--static-pose", settings->request.static_pose,
                     "the pose held in the static trial (--static, or a static stretch): zero, t-pose, "
                     "a-pose or a pose CSV (its first row); default: the one nearest the tracked posture");
      app.add_option("--static-posture", settings->request.static_posture,
                     "near (the posture held is estimated within --static-sd of the reference pose), "
                     "exact (every frame within --static-sd of it) or auto (exact, within 0.5 degrees or "
                     "--static-sd if less, and the pelvis upright within as much, where a segment of the "
                     "static trial carries only markers placed by their motion, else near)")
          ->check(CLI::IsMember({"auto", "near", "exact"}));
      // Deprecated (what --static does now): hidden, and run_track says what replaced it.
      app.add_flag("--static-refine", settings->request.static_refine)->group("");
      app.add_flag("!--no-static-stretch", settings->request.static_stretch,
                   "without --static: do not take a stretch of the recording in which the subject stands "
                   "still (1 s or more) in a reference pose as its static trial (default: it is, and "
                   "the calibration on the recording starts from the subject calibrated there)");
      app.add_flag("!--no-calibrate", settings->request.calibrate,
                   "track with the marker set as it is (default: calibrate marker offsets and bone lengths "
                   "on stretches of frames spread over the recording)");
      app.add_option("--calibration-frames", settings->request.calibration_frames,
                     "frames the calibration uses, in stretches spread over the recording")
          ->check(CLI::Range(10, 10000000));
      app.add_option("--calibration-samples", settings->request.calibration_samples,
                     "S2KF sample count of the calibration's tracking pass (0: --samples; fewer are "
                     "faster but move the calibration, docs/benchmarks.md)")
          ->check(CLI::Range(3, 100001));
      app.add_option("--calibration-shrink", settings->request.calibration_shrink,
                     "pull the marker offsets the recording sees only weakly towards the marker set: "
                     "a direction keeps mu / (mu + C) of the data's step (0: none)")
          ->check(CLI::Range(0.0, 1e6));
      app.add_flag(
          "--uniform-noise", settings->request.uniform_noise,
          "give every marker the same noise (default: after calibrating, each marker's noise follows its "
          "calibration residual, 0.5-2 times the common 10 mm)");
      app.add_flag(
          "--smooth", settings->request.smooth,
          "offline Rauch-Tung-Striebel smoothing of the S2KF's motion (about 17 KB per frame in memory)");
      app.add_option("--figure", settings->figure_frame,
                     "draw frame F (0-based) as tracked: PREFIX_frameF.png/.svg, data and gnuplot script")
          ->check(CLI::NonNegativeNumber);
      app.add_option(
          "--truth", settings->request.truth,
          "ground-truth motion CSV (s2kf simulate's _truth.csv): adds the accuracy to the summary");
      app.add_flag("--realtime", settings->realtime,
                   "pace frames at the recording's rate and count deadline misses");
      app.add_flag("--force", settings->request.force,
                   "track even a recording whose inferred marker set does not look like a whole body");
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
