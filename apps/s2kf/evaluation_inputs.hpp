/// @file
/// What `s2kf evaluate` runs on when it simulates: the recording and the subject it was drawn on,
/// and the references only a known subject allows (evaluation_inputs.cpp).
#pragma once

#include "evaluate_run.hpp"

#include <s2kf/io/motion_files.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

#include <nlohmann/json.hpp>

namespace s2kf::cli {

/// A recording simulated here, with the subject it was drawn on (for the true-subject reference).
struct Simulated {
  sim::Subject subject;
  sim::Recording recording;
};

/// The recording --motion asks for, on a realistic subject drawn with --subject-seed (with
/// --occlusion applied), and that subject.
Simulated simulate_for_evaluation(const EvaluateSettings& settings);

/// The identifiable-subject references (identifiable_subject_reference.hpp): the true subject
/// with the part the calibration frames' data cannot determine reset to the marker set's values,
/// then the true-subject fit with it. The thresholds are CalibrationOptions::prior_only_fraction's
/// (a direction's information against a marker coordinate's seen in every calibration frame):
/// 1e-5, the exact gauges (they lie below 2e-6, the first direction the data do see above 4e-5,
/// on a subject without soft tissue); 0.03, a looser one, which leaves the weakly seen directions
/// to the prior too; and "nominal", every direction reset: the nominal model itself, what
/// calibrating can improve on. The frames and priors are the default calibration's; empty when
/// the recording's marker set is not the model's.
nlohmann::json identifiable_references(const pipeline::Session& setup, const Simulated& simulated,
                                       const io::MotionTable& truth, long warmup);

/// The best constant placement (best_constant_placement: each marker where the recording shows it
/// on average in its segment's frame at the true poses, the subject's true bone lengths), fitted
/// frame by frame like the true-subject fit: what a constant subject gives once every pose is
/// known, soft tissue's average included in the placement. "identifiable": the same with its
/// exact gauges (threshold 1e-5) reset to the marker set's, the most a calibration could recover
/// of it; null when the recording's marker set is not the model's.
nlohmann::json constant_placement_reference(const pipeline::Session& setup, const Simulated& simulated,
                                            const io::MotionTable& truth, long warmup);

/// The default calibration's bundle adjustment on its own frames, started at their true poses
/// (adjust_subject_at_poses) instead of the tracker's, then the per-frame fit with that subject:
/// where the calibration's objective itself lands. Null when the marker set is not the model's.
nlohmann::json calibration_at_true_poses_reference(const pipeline::Session& setup, const Simulated& simulated,
                                                   const io::MotionTable& truth, long warmup);

}  // namespace s2kf::cli
