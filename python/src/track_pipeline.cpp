// s2kf.track's work without Python (track_pipeline.hpp).
#include "track_pipeline.hpp"

#include "calibrated_subject.hpp"  // apps/s2kf: a subject calibrated on a static trial
#include "marker_set_json.hpp"     // apps/s2kf: bundled marker sets, the automatic choice, messages
#include "track_summary.hpp"       // apps/s2kf: the summary `s2kf track` writes

#include <s2kf/io/sample_cache.hpp>
#include <s2kf/track/tracking_smoother.hpp>

#include <memory>
#include <stdexcept>

namespace s2kf::python {
namespace {

/// Memory --smooth may take before it refuses a recording (as `s2kf track`).
constexpr double kSmoothingMemoryLimitBytes = 8e9;

}  // namespace

std::unique_ptr<TrackResult> run_pipeline(FrameSource& source, const std::string& input,
                                          const std::string& name, const std::vector<std::string>& raw_labels,
                                          const std::vector<std::string>& file_warnings,
                                          const TrackSettings& settings) {
  if (settings.smooth && settings.method != "s2kf")
    throw cli::UserError(
        "smooth works on the S2KF's estimates; it cannot be combined with method='baseline'");
  if (source.frame_count() == 0) throw cli::UserError(input + ": the recording holds no complete frame");
  if (settings.smooth && static_cast<double>(source.frame_count()) * track::TrackingSmoother::kBytesPerFrame >
                             kSmoothingMemoryLimitBytes)
    throw cli::UserError(
        input + ": " + std::to_string(source.frame_count()) +
        " frames are too many to smooth in memory; track without smoothing, or split the recording");
  if (!settings.static_trial.empty() && !settings.subject.empty())
    throw cli::UserError(
        "give static or subject, not both (static calibrates the subject on the static trial)");
  if (!settings.static_trial.empty() && !settings.calibrate)
    throw cli::UserError(
        "static calibrates the subject on the static trial; it cannot be combined with calibrate=False");
  auto result = std::make_unique<TrackResult>();
  result->samples = lcd_sample_set(6 + body::kJointCount,
                                   settings.samples > 0 ? settings.samples : track::TrackerOptions{}.samples)
                        .set;
  cli::MarkerSetChoice choice;
  if (!settings.static_trial.empty()) {
    // As `s2kf track --static`: the subject calibrated on the static trial in the model's zero
    // pose (`s2kf calibrate --static`), then the recording tracked with it as with a subject file.
    const cli::CalibratedSubject calibrated = cli::calibrate_subject_file(
        settings.static_trial, "static",
        cli::static_trial_settings(settings.markerset, settings.height_mm, !settings.uniform_noise,
                                   settings.static_sd_deg),
        result->samples, name + "_subject");
    choice.set = calibrated.subject;
    choice.source = "calibrated on the static trial " + settings.static_trial;
  } else {
    choice = cli::choose_marker_set_for(source.labels(), settings.markerset, settings.subject);
  }
  pipeline::SessionOptions session_options;
  try {
    session_options.tracker = track::preset_options(settings.preset, source.rate_hz());
    track::set_gain_from_name(session_options.tracker, settings.gain);
  } catch (const std::invalid_argument& e) {
    throw cli::UserError(e.what());
  }
  if (settings.samples > 0) session_options.tracker.samples = settings.samples;
  session_options.height_mm = settings.height_mm;
  session_options.calibrate = settings.calibrate && settings.subject.empty() && settings.static_trial.empty();
  session_options.calibration_frames = settings.calibration_frames;
  session_options.calibration.weak_direction_shrink = settings.calibration_shrink;
  session_options.noise_from_calibration = !settings.uniform_noise;

  result->name = name;
  result->point_count = static_cast<Eigen::Index>(source.labels().size());
  pipeline::Session& session = result->session;
  try {
    session = pipeline::prepare_session(source, choice.set, session_options, result->samples);
  } catch (const std::invalid_argument& e) {
    throw cli::UserError(input + ": " + e.what());
  }
  // Model outputs never match a marker; the summary lists each under its own name in the file.
  // The ignored labels are in point order, one per unmatched point, "" for every model output.
  std::vector<std::string> output_names;
  for (std::size_t p = 0; p < raw_labels.size(); ++p)
    if (source.labels()[p].empty()) output_names.push_back(raw_labels[p]);
  std::size_t next_output = 0;
  for (std::string& label : session.mapping.ignored_labels)
    if (label.empty() && next_output < output_names.size()) label = output_names[next_output++];
  std::vector<std::string> warnings = file_warnings;
  warnings.insert(warnings.end(), session.warnings.begin(), session.warnings.end());
  result->messages = cli::marker_set_messages(choice, session.mapping);

  pipeline::RunOptions run_options;
  run_options.method = settings.method == "s2kf" ? pipeline::Method::s2kf : pipeline::Method::baseline;
  run_options.smooth = settings.smooth;
  track::TrackingRun& run = result->run;
  try {
    run = pipeline::run_session(session, source, result->samples, run_options);
  } catch (const std::invalid_argument& e) {
    throw cli::UserError(input + ": " + e.what());
  }
  if (run.frames_tracked == 0)
    throw cli::UserError(input + ": no frame has the " +
                         std::to_string(session.tracker.min_markers_to_start) +
                         " visible markers needed to start tracking");
  warnings.insert(warnings.end(), run.warnings.begin(), run.warnings.end());

  // The summary, field for field as `s2kf track` writes PREFIX.json (the same builder).
  result->summary = cli::track_summary(input, settings.method, choice, result->messages, session, run,
                                       settings.smooth, warnings, settings.calibration_shrink);
  return result;
}

}  // namespace s2kf::python
