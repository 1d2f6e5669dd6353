// What `s2kf evaluate` runs on when it simulates (evaluation_inputs.hpp).
#include "evaluation_inputs.hpp"

#include "bundled_motions.hpp"
#include "command.hpp"
#include "evaluation_files.hpp"
#include "marker_set_json.hpp"
#include "motion_json.hpp"
#include "track_summary.hpp"
#include "tracker_samples.hpp"

#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>
#include <s2kf/track/evaluation.hpp>
#include <s2kf/track/hidden_time_error.hpp>
#include <s2kf/track/identifiable_subject_reference.hpp>
#include <s2kf/track/session.hpp>
#include <s2kf/track/true_subject_reference.hpp>

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>

namespace s2kf::cli {

using nlohmann::json;

Simulated simulate_for_evaluation(const EvaluateSettings& settings) {
  if (!settings.recording.empty() || !settings.truth.empty())
    throw UserError("--motion simulates the recording and its truth: give no recording or --truth with it");
  sim::SubjectOptions subject_options;  // the realistic defaults (docs/simulation.md)
  const body::BodyModel base = body::mmm_body_model(subject_options.height_mm);
  Simulated simulated{sim::make_subject(base, subject_options, settings.subject_seed), {}};
  sim::RecordingOptions options;
  options.frames = settings.frames;
  if (!settings.occlusion.empty()) options.occlusion = occlusion_option(settings.occlusion);
  const std::filesystem::path file = resolve_motion(settings.motion);
  try {
    const JointTable joints{simulated.subject.joint_names, simulated.subject.lower, simulated.subject.upper};
    const sim::KeyframeMotion motion = load_motion_file(file, joints, settings.subject_seed);
    simulated.recording = sim::simulate_recording(motion, simulated.subject, options, settings.subject_seed);
  } catch (const std::exception& e) {
    throw UserError(file.string() + ": " + e.what());
  }
  return simulated;
}

/// The identifiable-subject references (identifiable_subject_reference.hpp): the true subject
/// with the part the calibration frames' data cannot determine reset to the marker set's values,
/// then the true-subject fit with it. The thresholds are CalibrationOptions::prior_only_fraction's
/// (a direction's information against a marker coordinate's seen in every calibration frame):
/// 1e-5, the exact gauges (they lie below 2e-6, the first direction the data do see above 4e-5,
/// on a subject without soft tissue); 0.03, a looser one, which leaves the weakly seen directions
/// to the prior too; and "nominal", every direction reset: the nominal model itself, what
/// calibrating can improve on. The frames and priors are the default calibration's; empty when
/// the recording's marker set is not the model's.
json identifiable_references(const track::Session& setup, const Simulated& simulated,
                             const io::MotionTable& truth, long warmup) {
  const track::SessionOptions defaults;
  track::CalibrationOptions calibration = defaults.calibration;
  calibration.marker_weight = track::calibration_weights(setup.marker_set, setup.tracker.marker_noise_mm);
  const std::vector<long> frames = track::calibration_frame_indices(
      track::calibration_stretches(simulated.recording.frames(), defaults.calibration_frames,
                                   defaults.calibration_windows),
      calibration);
  // The model the calibration starts from (prepare_session's, before the calibration).
  const body::BodyModel nominal =
      body::apply_marker_set(body::mmm_body_model(setup.marker_set.reference_height_mm), setup.marker_set)
          .scaled(setup.height_mm);
  json references = json::array();
  for (const double fraction : {1e-5, 0.03, std::numeric_limits<double>::infinity()}) {
    track::IdentifiableSubject identifiable;
    try {
      identifiable = track::identifiable_subject(nominal, simulated.subject, simulated.recording, frames,
                                                 calibration, setup.tracker.marker_noise_mm, fraction);
    } catch (const std::invalid_argument&) {
      return json::array();  // another marker set: no common unknowns to compare
    }
    sim::Subject subject = simulated.subject;
    subject.model = identifiable.model;
    const track::TruthComparison fit = track::compare_with_truth(
        setup.model, track::true_subject_fit(subject, simulated.recording), truth, warmup);
    references.push_back({{"prior_only_fraction", std::isinf(fraction) ? json("nominal") : json(fraction)},
                          {"information_ratio_threshold", number_or_null(identifiable.threshold)},
                          {"reset_directions", identifiable.reset_directions},
                          {"subject_unknowns", identifiable.information_ratios.size()},
                          {"frames_used", identifiable.frames_used},
                          {"truth", truth_json(fit)}});
  }
  return references;
}

}  // namespace s2kf::cli
