/// @file
/// The definitions of <s2kf/calibration/subject_information.hpp>: inline where the library is used
/// header-only, compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/calibration/bundle_adjustment.hxx>
#include <s2kf/calibration/subject_information.hpp>

namespace s2kf::calibration {
S2KF_INLINE SubjectInformation subject_information(const body::BodyModel& start, const body::BodyModel& model,
                                                   const body::MarkerMapping& mapping,
                                                   const MarkerSequence& recording,
                                                   const std::vector<std::pair<long, body::Pose>>& poses,
                                                   const CalibrationOptions& options, double noise_variance,
                                                   double prior_only_fraction) {
  detail::BundleAdjustment adjustment(start, mapping, recording, options, noise_variance);
  const std::vector<detail::BundleFrame> frames =
      detail::frames_at_poses(mapping, recording, adjustment.used(), poses, model.joint_count(), false);
  SubjectInformation result;
  result.segments = adjustment.segments();
  result.frames_used = static_cast<long>(frames.size());
  result.threshold = adjustment.prior_only_threshold(prior_only_fraction, static_cast<double>(frames.size()));
  if (!frames.empty())
    result.information = adjustment.information_in_prior_metric(model, frames, result.prior_sd);
  return result;
}
}  // namespace s2kf::calibration
