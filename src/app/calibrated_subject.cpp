// A subject estimated from one recording (calibrated_subject.hpp).
#include <s2kf/app/calibrated_subject.hpp>

#include <s2kf/app/track_summary.hpp>  // fixed_text

#include <s2kf/core/constants.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_frame_source.hpp>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace s2kf::app {

CalibratedSubject calibrate_subject(FrameSource& source, const std::string& input,
                                    const SubjectSettings& settings, const SampleSet& samples,
                                    const std::string& name) {
  CalibratedSubject result;
  result.choice = choose_marker_set_for(source.labels(), settings.markerset, "");
  pipeline::SessionOptions options;
  options.height_mm = settings.height_mm;
  options.fallback_height_mm = 0;  // a subject file needs a real height: refuse instead
  options.calibrate = true;
  options.calibration_may_fail = false;
  options.calibration_frames = settings.frames;
  options.calibration.iterations = settings.iterations;
  options.calibration.final_pass = true;
  options.calibration.threads = settings.threads;
  options.calibration.estimate_segment_scales = !settings.no_scales;
  options.calibration.weak_direction_shrink = settings.shrink;
  options.noise_from_calibration = settings.noise_from_calibration;
  if (settings.static_pose)
    options.calibration.static_pose_sd_rad = settings.static_sd_deg / kDegreesPerRadian;
  try {
    result.session = pipeline::prepare_session(source, result.choice.set, options, samples);
  } catch (const std::invalid_argument& e) {
    throw UserError(input + ": " + e.what());
  }
  const calibration::SubjectCalibration& calibration = *result.session.calibration;
  result.subject = subject_marker_set(result.choice.set, calibration.model, calibration.segment_scale,
                                      result.session.tracker.marker_noise_mm_per_marker, name);
  result.messages = marker_set_messages(result.choice, result.session.mapping);
  return result;
}

CalibratedSubject calibrate_subject_file(const std::string& path, const std::string& what,
                                         const SubjectSettings& settings, const SampleSet& samples,
                                         const std::string& name) {
  std::unique_ptr<c3d::C3dFrameSource> source;
  try {
    source = std::make_unique<c3d::C3dFrameSource>(path);
  } catch (const std::exception& e) {
    throw UserError(what.empty() ? std::string(e.what()) : what + ": " + e.what());
  }
  return calibrate_subject(*source, what.empty() ? path : what + " " + path, settings, samples, name);
}

SubjectSettings static_trial_settings(const std::string& markerset, double height_mm,
                                      bool noise_from_calibration, double static_sd_deg) {
  SubjectSettings settings;
  settings.markerset = markerset;
  settings.height_mm = height_mm;
  settings.noise_from_calibration = noise_from_calibration;
  settings.static_pose = true;
  settings.static_sd_deg = static_sd_deg;
  settings.threads = every_core();
  return settings;
}

void write_subject_file(const std::string& path, const nlohmann::json& document) {
  io::write_file_atomically(path, [&](std::ostream& out) { out << document.dump(2) << "\n"; });
}

nlohmann::json subject_document(const CalibratedSubject& calibrated, const std::string& input) {
  nlohmann::json document = marker_set_to_json(calibrated.subject);
  const calibration::SubjectCalibration& calibration = *calibrated.session.calibration;
  // The loader rejects unknown keys, so the subject file carries only a one-line summary of the
  // calibration in its description.
  document["description"] = calibrated.subject.description + " on " +
                            std::filesystem::path(input).filename().string() + "; mean marker distance " +
                            fixed_text(calibration.mean_marker_distance_before_mm, 1) + " mm before, " +
                            fixed_text(calibration.mean_marker_distance_after_mm, 1) + " mm after";
  return document;
}

}  // namespace s2kf::app
