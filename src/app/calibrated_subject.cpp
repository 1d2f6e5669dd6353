// A subject estimated from one recording (calibrated_subject.hpp).
#include <s2kf/app/calibrated_subject.hpp>

#include <s2kf/app/track_summary.hpp>  // fixed_text

#include <s2kf/body/reference_poses.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/io/motion_files.hpp>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace s2kf::app {

namespace fs = std::filesystem;

void apply_static_settings(const SubjectSettings& settings, calibration::CalibrationOptions& options) {
  options.static_pose_sd_rad = settings.static_sd_deg / kDegreesPerRadian;
  options.static_posture_estimated = settings.static_posture == "near";
  options.static_upright_sd_rad = settings.static_upright_sd_deg / kDegreesPerRadian;
  const body::BodyModel base = body::mmm_body_model(1000);
  if (settings.static_pose_name.empty())
    for (const std::string& name : body::reference_pose_names())
      options.static_pose_candidates.push_back(body::reference_pose(base, name));
  else
    options.static_pose = static_reference_pose(base, settings.static_pose_name, settings.static_pose_option);
}

CalibratedSubject calibrate_subject(FrameSource& source, const std::string& input,
                                    const SubjectSettings& settings, const SampleSet& samples,
                                    const std::string& name) {
  CalibratedSubject result;
  result.choice = settings.set ? MarkerSetChoice{*settings.set, "given", {}, {}}
                               : choose_marker_set_for(source.labels(), settings.markerset, "");
  pipeline::SessionOptions options;
  options.height_mm = settings.height_mm;
  options.fallback_height_mm = 0;  // a subject file needs a real height: refuse instead
  options.calibrate = true;
  options.calibration_may_fail = false;
  options.calibration_frames = settings.frames;
  options.calibration.iterations = settings.iterations;
  options.calibration.final_pass = settings.final_pass;
  options.calibration.threads = settings.threads;
  options.calibration.estimate_segment_scales = !settings.no_scales;
  options.calibration.weak_direction_shrink = settings.shrink;
  options.noise_from_calibration = settings.noise_from_calibration;
  options.subject_limits.max_side_ratio = settings.max_side_ratio;
  if (settings.static_pose) apply_static_settings(settings, options.calibration);
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
                                      bool noise_from_calibration, double static_sd_deg,
                                      const std::string& static_pose_name,
                                      const std::string& static_posture) {
  SubjectSettings settings;
  settings.markerset = markerset;
  settings.height_mm = height_mm;
  settings.noise_from_calibration = noise_from_calibration;
  settings.static_pose = true;
  settings.static_sd_deg = static_sd_deg;
  settings.static_pose_name = static_pose_name;
  settings.static_posture = static_posture;
  settings.threads = every_core();
  return settings;
}

Eigen::VectorXd static_reference_pose(const body::BodyModel& model, const std::string& name,
                                      const std::string& option) {
  if (body::is_reference_pose(name)) return body::reference_pose(model, name);
  if (!fs::exists(name))
    throw UserError(option + ": '" + name + "' is neither zero, t-pose, a-pose nor an existing pose CSV");
  io::MotionTable table;
  try {
    table = io::load_motion_csv(name);
  } catch (const std::exception& e) {
    throw UserError(option + ": " + name + ": " + e.what());
  }
  if (table.frames() == 0) throw UserError(option + ": " + name + " holds no pose row");
  Eigen::VectorXd joints(model.joint_count());
  for (int j = 0; j < model.joint_count(); ++j) {
    const auto found = std::find(table.joint_names.begin(), table.joint_names.end(), model.joints[j].name);
    if (found == table.joint_names.end())
      throw UserError(option + ": " + name + " has no column " + model.joints[j].name +
                      " (a pose CSV needs every joint, as s2kf track writes them)");
    joints(j) = table.values(0, body::kRootValues + (found - table.joint_names.begin()));
  }
  if (!joints.allFinite())
    throw UserError(option + ": " + name + ": the first row's joint angles are not all numbers");
  return joints;
}

Eigen::VectorXd static_reference_used(const calibration::SubjectCalibration& calibration,
                                      const std::string& name, const std::string& option) {
  if (calibration.static_pose_choice >= 0)
    return body::reference_pose(
        calibration.model,
        body::reference_pose_names()[static_cast<std::size_t>(calibration.static_pose_choice)]);
  return static_reference_pose(calibration.model, name.empty() ? "zero" : name, option);
}

std::string static_posture_text(const CalibratedSubject& calibrated, const SubjectSettings& settings) {
  const calibration::SubjectCalibration& calibration = *calibrated.session.calibration;
  std::string pose = settings.static_pose_name == "zero" ? "zero pose" : settings.static_pose_name;
  if (pose.empty() && calibration.static_pose_choice >= 0) {
    pose = body::reference_pose_names()[static_cast<std::size_t>(calibration.static_pose_choice)];
    pose = (pose == "zero" ? "zero pose" : pose) + " (found from the data)";
  }
  if (calibration.static_posture.size() == 0) return pose;
  const Eigen::VectorXd reference =
      static_reference_used(calibration, settings.static_pose_name, settings.static_pose_option);
  const Eigen::VectorXd off = (calibration.static_posture - reference) * kDegreesPerRadian;
  Eigen::Index worst = 0;
  off.cwiseAbs().maxCoeff(&worst);
  return pose + ", posture held " +
         fixed_text(std::sqrt(off.squaredNorm() / static_cast<double>(off.size())), 1) +
         " deg RMS from it (most " + calibration.model.joints[static_cast<std::size_t>(worst)].name + ", " +
         fixed_text(off(worst), 1) + " deg" +
         (std::abs(off(worst)) > 25 ? "; far from it: was that the pose held?" : "") + ")";
}

void write_subject_file(const std::string& path, const nlohmann::json& document) {
  io::write_file_atomically(path, [&](std::ostream& out) { out << document.dump(2) << "\n"; });
}

nlohmann::json subject_document(const CalibratedSubject& calibrated, const std::string& input) {
  const calibration::SubjectCalibration& calibration = *calibrated.session.calibration;
  return subject_document(calibrated.subject, calibration.mean_marker_distance_before_mm,
                          calibration.mean_marker_distance_after_mm,
                          std::filesystem::path(input).filename().string());
}

nlohmann::json subject_document(const body::MarkerSet& subject, double before_mm, double after_mm,
                                const std::string& inputs) {
  nlohmann::json document = marker_set_to_json(subject);
  // The loader rejects unknown keys, so the subject file carries only a one-line summary of the
  // calibration in its description.
  document["description"] = subject.description + " on " + inputs + "; mean marker distance " +
                            fixed_text(before_mm, 1) + " mm before, " + fixed_text(after_mm, 1) + " mm after";
  return document;
}

}  // namespace s2kf::app
