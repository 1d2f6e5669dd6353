/// @file
/// A subject estimated from one recording, as `s2kf calibrate` estimates it and as `s2kf track
/// --static --static-alone` does before tracking: the session with its calibration, and the calibrated
/// subject as the marker set a subject file holds.
#pragma once

#include <s2kf/app/marker_set_json.hpp>

#include <s2kf/core/parallel_for.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/pipeline/session.hpp>

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace s2kf::app {

/// The options of `s2kf calibrate` (and of a static trial's calibration in `s2kf track --static`).
struct SubjectSettings {
  std::string markerset;               ///< empty: the bundled set that matches best
  std::optional<body::MarkerSet> set;  ///< the marker set itself, chosen already (markerset is then unused)
  double height_mm = 0;                ///< 0: estimate
  int iterations = 1;
  long frames = 1200;
  bool no_scales = false;
  double shrink = calibration::CalibrationOptions{}.weak_direction_shrink;
  bool noise_from_calibration = true;
  bool static_pose = false;  ///< a static trial
  /// The posture held there: zero, t-pose, a-pose or a pose CSV (its first row); empty: the
  /// reference pose nearest the tracked posture.
  std::string static_pose_name;
  std::string static_pose_option = "--static-pose";  ///< names the pose in messages
  double static_sd_deg = 3.0;
  /// "near": static_sd_deg is the SD of the posture held over the trial (estimated near the
  /// reference); "exact": of every frame's angles (the reference taken as held).
  std::string static_posture = "near";
  /// > 0: the static trial's pelvis is held upright within this SD (degrees) of the lab's vertical
  /// (calibration::CalibrationOptions::static_upright_sd_rad); 0: its tilt is free.
  double static_upright_sd_deg = 0;
  int threads = 1;  ///< the calibration's threads (every_core() for all)
  /// Track the recording once more with the calibrated subject for its mean marker distance after
  /// calibration; false where nobody reads it (a still stretch tried as a static trial).
  bool final_pass = true;
  /// A static trial's left and right bone-length factors may differ by at most this ratio
  /// (calibration::CalibrationLimits::max_side_ratio).
  double max_side_ratio = calibration::CalibrationLimits{}.max_side_ratio;
};

struct CalibratedSubject {
  MarkerSetChoice choice;
  pipeline::Session session;  ///< with its calibration
  body::MarkerSet subject;
  std::vector<std::string> messages;  ///< which marker set and why, labels ignored
};

/// The calibration's static-trial options (its posture's SD, near or exact, the reference pose or
/// the candidates to find it among) from `settings`.
void apply_static_settings(const SubjectSettings& settings, calibration::CalibrationOptions& options);

/// Calibrates the subject of the recording `source` (`input` names it in messages), with the
/// tracker's `samples`; the subject is named `name`. Throws UserError naming the recording when
/// the calibration cannot run (no height, too few markers).
CalibratedSubject calibrate_subject(FrameSource& source, const std::string& input,
                                    const SubjectSettings& settings, const SampleSet& samples,
                                    const std::string& name);

/// calibrate_subject on the C3D file `path`. A file the reader refuses is a UserError: its
/// sentence, after "`what`: " when `what` (the option that named the file) is given.
CalibratedSubject calibrate_subject_file(const std::string& path, const std::string& what,
                                         const SubjectSettings& settings, const SampleSet& samples,
                                         const std::string& name);

/// The settings of a static trial's calibration, with every core (`s2kf track --static`,
/// `s2kf.track(static=...)`, alone or together with the recording).
SubjectSettings static_trial_settings(const std::string& markerset, double height_mm,
                                      bool noise_from_calibration, double static_sd_deg,
                                      const std::string& static_pose_name = "",
                                      const std::string& static_posture = "near");

/// The static trial's reference pose named `name` (zero, t-pose, a-pose, or a pose CSV whose first
/// row is used) for `model`; a UserError naming `option` for anything else.
Eigen::VectorXd static_reference_pose(const body::BodyModel& model, const std::string& name,
                                      const std::string& option);

/// The reference pose a static calibration measured its posture against: the pose it found from
/// the data, else the one named `name` (empty: the zero pose; `option` names it in errors).
Eigen::VectorXd static_reference_used(const calibration::SubjectCalibration& calibration,
                                      const std::string& name, const std::string& option);

/// What the calibration found of a static trial: the reference pose and how far the posture
/// held was from it, for messages and reports.
std::string static_posture_text(const CalibratedSubject& calibrated, const SubjectSettings& settings);

/// The subject file's document: the marker set, described with the recording it came from and
/// the calibration's mean marker distance before and after.
nlohmann::json subject_document(const CalibratedSubject& calibrated, const std::string& input);

/// The same for `subject`, calibrated on the recordings `inputs` names ("static.c3d and walk.c3d")
/// from a mean marker distance of `before_mm` to `after_mm`.
nlohmann::json subject_document(const body::MarkerSet& subject, double before_mm, double after_mm,
                                const std::string& inputs);

/// Writes a subject file's document to `path`, completely or not at all.
void write_subject_file(const std::string& path, const nlohmann::json& document);

}  // namespace s2kf::app
