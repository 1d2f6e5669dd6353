/// @file
/// The reachable reference on a simulated recording: what the best possible calibration could
/// recover of the subject. Some directions of the subject (bone-length factors and marker offsets)
/// are gauges: turning all markers of a foot about its 3-DoF ankle is undone by a constant offset
/// of the ankle's angles, so the markers fit exactly as well either way and no calibration can
/// tell them from the data; its priors keep them at the marker set's (nominal) values. The
/// identifiable subject is the true subject with exactly that part reset to the nominal: the
/// true-minus-nominal difference is kept only along the directions the calibration frames'
/// data determine. Those come from the model and the recording the way the bundle adjustment sees
/// them (its reduced normal matrix at the true poses, the poses eliminated, in the priors' metric,
/// BundleAdjustment::information_in_prior_metric). The per-frame fit with that subject, started
/// at the true pose (true_subject_fit), is then the reference a calibration can reach, where the
/// true-subject fit is one it cannot.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

namespace s2kf::evaluation {

/// The frames of a recording the calibration adjusts: in each stretch (first frame, count) it
/// reads, every options.stride-th frame from options.skip_frames after the stretch's start (the
/// tracker starts afresh at each stretch).
inline std::vector<long> calibration_frame_indices(
    const std::vector<std::pair<std::int64_t, std::int64_t>>& stretches,
    const calibration::CalibrationOptions& options) {
  std::vector<long> frames;
  for (const auto& [first, count] : stretches)
    for (std::int64_t k = options.skip_frames; k < count; k += options.stride)
      frames.push_back(static_cast<long>(first + k));
  return frames;
}

struct IdentifiableSubject {
  body::BodyModel model;  ///< the true subject, its undetermined part reset to the nominal
  /// Eigenvalues of the data information in the priors' metric (data over prior information along
  /// each eigenvector), ascending, one per subject unknown.
  Eigen::VectorXd information_ratios;
  double threshold = 0;      ///< the information ratio below which a direction is reset
  int reset_directions = 0;  ///< eigenvectors below the threshold: reset to the nominal
  long frames_used = 0;      ///< calibration frames with 3 or more visible markers
};

/// The identifiable subject of `subject` on `recording` (simulated on it) against `nominal` (the
/// model the calibration starts from: the same joints and markers in the same order, e.g. the
/// marker set applied and scaled to the subject's height). The data information is formed at the
/// true poses of `frames` (calibration_frame_indices) with the priors and marker weights of
/// `options` and the marker noise `marker_noise_mm`; the subject difference true - nominal is kept
/// along the eigenvectors whose data-over-prior information ratio reaches `prior_only_fraction`
/// times that of a marker coordinate seen in every frame (CalibrationOptions::prior_only_fraction's
/// threshold) and reset to the nominal along the others. 0 keeps the true subject; infinity gives
/// the nominal.
IdentifiableSubject identifiable_subject(const body::BodyModel& nominal, const sim::Subject& subject,
                                         const sim::Recording& recording, const std::vector<long>& frames,
                                         const calibration::CalibrationOptions& options,
                                         double marker_noise_mm, double prior_only_fraction);

}  // namespace s2kf::evaluation

#if !defined(S2KF_COMPILED)
#include <s2kf/evaluation/identifiable_subject_reference.hxx>
#endif
