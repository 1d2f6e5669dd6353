// `s2kf calibrate`: estimate a subject (body height, bone lengths, where each marker sits) from a
// recording of that subject, and write it as a marker-set file `s2kf track --subject` loads.
#include <s2kf/app/calibrated_subject.hpp>
#include <s2kf/app/extra_outputs.hpp>
#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/app/sample_sets.hpp>
#include <s2kf/app/track_summary.hpp>  // fixed_text
#include "command.hpp"
#include "output_options.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/pipeline/session.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

namespace s2kf::cli {
namespace {

namespace fs = std::filesystem;

struct CalibrateSettings : SubjectSettings {
  std::string input;
  std::string out;
  bool quiet = false;
  double body_mass_kg = 0;  ///< --mass, for SUBJECT.osim
};

void run_calibrate(CalibrateSettings settings) {
  settings.threads = every_core();
  const std::string name = fs::path(settings.out).stem().string();
  const CalibratedSubject calibrated = calibrate_subject_file(
      settings.input, "", settings, cached_sample_set(46, track::TrackerOptions{}.samples), name);
  const pipeline::Session& session = calibrated.session;
  const calibration::SubjectCalibration& calibration = *session.calibration;
  const double height = session.height_mm;
  const std::string& height_source = session.height_source;

  const nlohmann::json document = subject_document(calibrated, settings.input);
  nlohmann::json passes = nlohmann::json::array();
  for (const calibration::CalibrationPass& pass : calibration.passes)
    passes.push_back({{"mean_marker_distance_mm", pass.mean_marker_distance_mm},
                      {"frames_used", pass.frames_used},
                      {"residuals_rejected", pass.residuals_rejected},
                      {"bundle_iterations", pass.bundle_iterations},
                      {"bundle_rms_before_mm", pass.rms_before_mm},
                      {"bundle_rms_after_mm", pass.rms_after_mm}});
  if (fs::path(settings.out).has_parent_path()) fs::create_directories(fs::path(settings.out).parent_path());
  const auto osim = prepare_subject_opensim_model(settings.out, calibration.model, session.mapping,
                                                  settings.body_mass_kg);  // SUBJECT.osim
  write_subject_file(settings.out, document);
  osim->commit();
  fs::path report = settings.out;
  report.replace_extension();
  const std::string report_path = report.string() + "_report.json";
  // The pass-by-pass report goes to a separate _report.json: the subject file's loader rejects
  // unknown keys.
  const nlohmann::json summary = {
      {"input", settings.input},
      {"marker_set", calibrated.choice.set.name},
      {"marker_set_source", calibrated.choice.source},
      {"height_mm", height},
      {"height_source", height_source},
      {"frames", session.calibration_frames},
      {"stretches", session.calibration_stretches},
      {"iterations", settings.iterations},
      {"weak_direction_shrink", settings.shrink},
      {"static_pose_sd_deg",
       settings.static_pose ? nlohmann::json(settings.static_sd_deg) : nlohmann::json(nullptr)},
      {"static_pose", settings.static_pose ? nlohmann::json(static_posture_text(calibrated, settings))
                                           : nlohmann::json(nullptr)},
      {"static_posture",
       settings.static_pose ? nlohmann::json(settings.static_posture) : nlohmann::json(nullptr)},
      {"segment_scale", calibration.segment_scale},
      {"passes", passes},
      {"mean_marker_distance_before_mm", calibration.mean_marker_distance_before_mm},
      {"mean_marker_distance_after_mm", calibration.mean_marker_distance_after_mm},
      {"warnings", session.warnings},
      {"messages", calibrated.messages}};
  io::write_file_atomically(report_path, [&](std::ostream& out) { out << summary.dump(2) << "\n"; });
  if (settings.quiet) return;
  for (const std::string& message : calibrated.messages) std::cout << message << "\n";
  for (const std::string& warning : session.warnings) std::cout << "warning: " << warning << "\n";
  std::cout << fs::path(settings.input).filename().string() << ": body height " << fixed_text(height, 0)
            << " mm (" << height_source << "); mean marker distance "
            << fixed_text(calibration.mean_marker_distance_before_mm, 1) << " mm with the marker set, "
            << fixed_text(calibration.mean_marker_distance_after_mm, 1) << " mm after " << settings.iterations
            << " calibration iteration(s)"
            << (settings.static_pose ? "; static trial in the " + static_posture_text(calibrated, settings)
                                     : "")
            << ".\nWrote " << settings.out << ", " << osim->path().string() << " and " << report_path
            << ".\n";
}

const RegisterCommand calibrate_registration{
    "calibrate", "Estimate a subject's marker offsets and bone lengths from a C3D recording",
    [](CLI::App& app) {
      auto settings = std::make_shared<CalibrateSettings>();
      app.add_option("recording", settings->input, "C3D recording of the subject")->required();
      app.add_option("--out", settings->out, "subject file to write (JSON marker set)")->required();
      app.add_option("--markerset", settings->markerset,
                     "bundled marker set (kit, cmu, plugin_gait) or a .json file (default: the best match)");
      app.add_option("--height", settings->height_mm, "subject height in mm (default: estimated)")
          ->check(CLI::Range(300.0, 3000.0));
      app.add_option("--iterations", settings->iterations,
                     "rounds of tracking and bundle adjustment (default 1)")
          ->check(CLI::Range(1, 20));
      app.add_option("--frames", settings->frames,
                     "frames used at most (default 1200): all of a shorter recording, else 4 stretches "
                     "spread over it")
          ->check(CLI::Range(10L, 1000000L));
      app.add_flag("--no-scales", settings->no_scales,
                   "keep the bone lengths, estimate the marker offsets only");
      app.add_option("--shrink", settings->shrink,
                     "pull the marker offsets the recording sees only weakly towards the marker set: "
                     "a direction keeps mu / (mu + C) of the data's step (default 0.03; 0: none)")
          ->check(CLI::Range(0.0, 1e6));
      app.add_flag("--static", settings->static_pose,
                   "the recording is a static trial, the subject standing still in a reference pose "
                   "(--static-pose): the posture fixes the markers' placement about the joints that no "
                   "moving recording can tell");
      app.add_option("--static-pose", settings->static_pose_name,
                     "with --static: the pose held, zero (upright, arms hanging, as `s2kf model` draws "
                     "it), t-pose, a-pose, or a pose CSV (its first row); default: the one nearest the "
                     "tracked posture");
      app.add_option("--static-sd", settings->static_sd_deg,
                     "with --static: how far (SD, degrees) each joint may be from the reference pose "
                     "(default 3)")
          ->check(CLI::Range(0.1, 90.0));
      app.add_option("--static-posture", settings->static_posture,
                     "with --static: near (default: the posture held is estimated within --static-sd of "
                     "the reference pose) or exact (every frame within --static-sd of it)")
          ->check(CLI::IsMember({"near", "exact"}));
      app.add_flag("!--uniform-noise", settings->noise_from_calibration,
                   "write no per-marker noise into the subject file (default: each marker's noise_mm "
                   "follows its calibration residual, 0.5-2 times the tracker's common 10 mm)");
      add_mass_option(app, settings->body_mass_kg);
      app.add_flag("--quiet", settings->quiet, "print nothing but errors");
      app.callback([settings] { run_calibrate(*settings); });
    }};

}  // namespace
}  // namespace s2kf::cli
