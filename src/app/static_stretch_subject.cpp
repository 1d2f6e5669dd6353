// A static trial found inside the recording (static_stretch_subject.hpp).
#include <s2kf/app/static_stretch_subject.hpp>

#include <s2kf/app/calibrated_subject.hpp>
#include <s2kf/app/track_summary.hpp>  // fixed_text
#include <s2kf/app/user_error.hpp>

#include <s2kf/body/marker_set_mapping.hpp>
#include <s2kf/calibration/static_stretch.hpp>
#include <s2kf/core/constants.hpp>

#include <cmath>
#include <limits>
#include <vector>

namespace s2kf::app {

StretchSubject static_stretch_subject(FrameSource& source, const std::string& input,
                                      const MarkerSetChoice& choice, const TrackRequest& request,
                                      const SampleSet& samples, int threads) {
  StretchSubject result;
  const body::MarkerMapping mapping = body::map_marker_set(source.labels(), choice.set);
  std::vector<bool> considered(source.labels().size(), false);
  for (int point : mapping.point_of_marker)
    if (point >= 0) considered[static_cast<std::size_t>(point)] = true;
  const std::optional<calibration::StaticStretch> stretch =
      calibration::find_static_stretch(source, considered);
  if (!stretch) return result;
  const double rate = source.rate_hz();
  const std::string where = "frames " + std::to_string(stretch->first) + "-" +
                            std::to_string(stretch->first + stretch->count - 1) + " (" +
                            fixed_text(static_cast<double>(stretch->count) / rate, 1) + " s)";
  SubjectSettings subject_settings = static_trial_settings(request);
  subject_settings.set = choice.set;
  subject_settings.threads = threads;
  subject_settings.frames = stretch->count;
  subject_settings.final_pass = false;  // only the subject and its posture are used here
  // Its subject is a start, calibrated again with the recording: its sides are not judged here
  // (test1's legs, straight throughout, give shanks of 1.01 and 0.76 from its still stretch).
  subject_settings.max_side_ratio = std::numeric_limits<double>::infinity();
  const MarkerSequence frames = read_frames(source, stretch->first, stretch->count);
  SequenceFrameSource still(frames);
  CalibratedSubject calibrated;
  try {
    calibrated = calibrate_subject(still, input + " " + where, subject_settings, samples, choice.set.name);
  } catch (const UserError& e) {
    result.message =
        where + " are still but no static trial (" + e.what() + "); calibrated on the recording alone";
    return result;
  }
  const calibration::SubjectCalibration& calibration = *calibrated.session.calibration;
  const Eigen::VectorXd reference =
      static_reference_used(calibration, request.static_pose, option_name(request, "static-pose"));
  Eigen::Index worst = 0;
  const double largest =
      (calibration.static_posture - reference).cwiseAbs().maxCoeff(&worst) * kDegreesPerRadian;
  if (!(largest <= kStaticStretchMaxJointOffsetDeg)) {
    result.message = where + " are still, but joint " +
                     calibration.model.joints[static_cast<std::size_t>(worst)].name + " is held " +
                     fixed_text(largest, 0) + " degrees off the nearest reference pose: no static " +
                     "trial; calibrated on the recording alone";
    return result;
  }
  result.subject = calibrated.subject;
  result.frames = frames;
  const std::string turn_off =
      request.names == OptionNames::program ? "--no-static-stretch" : "static_stretch=False";
  result.message = where + " are a static trial in the " + static_posture_text(calibrated, subject_settings) +
                   ": calibrated together with the recording (" + turn_off + ": not)";
  return result;
}

}  // namespace s2kf::app
