// What `s2kf evaluate` runs on when it simulates (evaluation_inputs.hpp).
#include "evaluation_inputs.hpp"

#include <s2kf/app/bundled_motions.hpp>
#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/app/motion_json.hpp>
#include <s2kf/app/sample_sets.hpp>
#include <s2kf/app/track_summary.hpp>
#include "evaluation_files.hpp"
#include "front_end.hpp"

#include <s2kf/evaluation/evaluation.hpp>
#include <s2kf/evaluation/hidden_time_error.hpp>
#include <s2kf/evaluation/identifiable_subject_reference.hpp>
#include <s2kf/evaluation/true_subject_reference.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

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

namespace {

/// What the default calibration works with on a simulated recording: its options (the marker
/// weights of the set), the frames it adjusts and the model it starts from.
struct DefaultCalibration {
  calibration::CalibrationOptions options;
  std::vector<long> frames;
  body::BodyModel nominal;
};

DefaultCalibration default_calibration(const pipeline::Session& setup, const Simulated& simulated) {
  const pipeline::SessionOptions defaults;
  DefaultCalibration c;
  c.options = defaults.calibration;
  c.options.marker_weight = pipeline::calibration_weights(setup.marker_set, setup.tracker.marker_noise_mm);
  c.frames = evaluation::calibration_frame_indices(
      pipeline::calibration_stretches(simulated.recording.frames(), defaults.calibration_frames,
                                      defaults.calibration_windows),
      c.options);
  // The model the calibration starts from (prepare_session's, before the calibration).
  c.nominal =
      body::apply_marker_set(body::mmm_body_model(setup.marker_set.reference_height_mm), setup.marker_set)
          .scaled(setup.height_mm);
  return c;
}

/// The true-subject fit with `model` in place of the subject's, against the truth.
evaluation::TruthComparison fit_with(const body::BodyModel& model, const pipeline::Session& setup,
                                     const Simulated& simulated, const io::MotionTable& truth, long warmup) {
  sim::Subject subject = simulated.subject;
  subject.model = model;
  return evaluation::compare_with_truth(
      setup.model, evaluation::true_subject_fit(subject, simulated.recording), truth, warmup);
}

bool same_markers(const pipeline::Session& setup, const Simulated& simulated) {
  return setup.model.marker_names() == simulated.subject.model.marker_names() &&
         setup.model.joint_names() == simulated.subject.model.joint_names();
}

json identifiable_json(const evaluation::IdentifiableSubject& identifiable, double fraction,
                       const evaluation::TruthComparison& fit) {
  return {{"prior_only_fraction", std::isinf(fraction) ? json("nominal") : json(fraction)},
          {"information_ratio_threshold", number_or_null(identifiable.threshold)},
          {"reset_directions", identifiable.reset_directions},
          {"subject_unknowns", identifiable.information_ratios.size()},
          {"frames_used", identifiable.frames_used},
          {"truth", truth_json(fit)}};
}

}  // namespace

json identifiable_references(const pipeline::Session& setup, const Simulated& simulated,
                             const io::MotionTable& truth, long warmup) {
  if (!same_markers(setup, simulated)) return json::array();  // no common unknowns to compare
  const DefaultCalibration c = default_calibration(setup, simulated);
  json references = json::array();
  for (const double fraction : {1e-5, 0.03, std::numeric_limits<double>::infinity()}) {
    evaluation::IdentifiableSubject identifiable;
    try {
      identifiable =
          evaluation::identifiable_subject(c.nominal, simulated.subject, simulated.recording, c.frames,
                                           c.options, setup.tracker.marker_noise_mm, fraction);
    } catch (const std::invalid_argument&) {
      return json::array();  // no calibration frame to form the information from
    }
    references.push_back(identifiable_json(identifiable, fraction,
                                           fit_with(identifiable.model, setup, simulated, truth, warmup)));
  }
  return references;
}

json constant_placement_reference(const pipeline::Session& setup, const Simulated& simulated,
                                  const io::MotionTable& truth, long warmup) {
  const sim::Subject constant = evaluation::best_constant_placement(simulated.subject, simulated.recording);
  json reference = {{"truth", truth_json(fit_with(constant.model, setup, simulated, truth, warmup))},
                    {"identifiable", nullptr}};
  if (same_markers(setup, simulated)) {
    const DefaultCalibration c = default_calibration(setup, simulated);
    constexpr double kExactGauges = 1e-5;
    const evaluation::IdentifiableSubject identifiable =
        evaluation::identifiable_subject(c.nominal, constant, simulated.recording, c.frames, c.options,
                                         setup.tracker.marker_noise_mm, kExactGauges);
    reference["identifiable"] = identifiable_json(
        identifiable, kExactGauges, fit_with(identifiable.model, setup, simulated, truth, warmup));
  }
  return reference;
}

json calibration_at_true_poses_reference(const pipeline::Session& setup, const Simulated& simulated,
                                         const io::MotionTable& truth, long warmup) {
  if (!same_markers(setup, simulated)) return nullptr;
  const DefaultCalibration c = default_calibration(setup, simulated);
  std::vector<std::pair<long, body::Pose>> poses;
  for (long k : c.frames) poses.emplace_back(k, simulated.recording.truth[static_cast<std::size_t>(k)]);
  const calibration::SubjectCalibration adjusted = calibration::adjust_subject_at_poses(
      c.nominal, body::map_markers(simulated.recording.labels, c.nominal.marker_names()), setup.tracker,
      simulated.recording, poses, c.options);
  const calibration::CalibrationPass& pass = adjusted.passes.front();
  return {{"frames_used", pass.frames_used},
          {"bundle_iterations", pass.bundle_iterations},
          {"bundle_rms_before_mm", pass.rms_before_mm},
          {"bundle_rms_after_mm", pass.rms_after_mm},
          {"truth", truth_json(fit_with(adjusted.model, setup, simulated, truth, warmup))}};
}

}  // namespace s2kf::cli
