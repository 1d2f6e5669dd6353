/// @file
/// The definitions of <s2kf/calibration/subject_calibration.hpp>: inline where the library is used
/// header-only, compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/calibration/bundle_adjustment.hxx>
#include <s2kf/calibration/subject_calibration.hpp>

namespace s2kf::calibration {

namespace detail {
/// The inputs given per model marker (the mapping, options.marker_weight and
/// options.placed_by_motion) have one entry for each of the model's markers; BundleAdjustment
/// reads them by marker index.
inline void check_per_marker_inputs(const body::BodyModel& model, const body::MarkerMapping& mapping,
                                    const CalibrationOptions& options) {
  const auto markers = static_cast<std::size_t>(model.marker_count());
  if (mapping.point_of_marker.size() != markers)
    throw std::invalid_argument("calibration: the marker mapping does not fit the body model");
  if (!options.marker_weight.empty() && options.marker_weight.size() != markers)
    throw std::invalid_argument("calibration: one weight per model marker is needed");
  if (!options.placed_by_motion.empty() && options.placed_by_motion.size() != markers)
    throw std::invalid_argument("calibration: one placed-by-motion flag per model marker is needed");
}
}  // namespace detail

S2KF_INLINE SubjectCalibration calibrate_subject(const body::BodyModel& model,
                                                 const body::MarkerMapping& mapping,
                                                 const track::TrackerOptions& tracker_options,
                                                 const MarkerSequence& recording, const SampleSet& samples,
                                                 const CalibrationOptions& options) {
  options.validate();
  model.validate();
  if (recording.visible.cols() != recording.positions.cols() ||
      recording.positions.rows() != 3 * recording.point_count())
    throw std::invalid_argument("calibration: one visibility flag per point and frame is needed");
  if (recording.frame_count() == 0) throw std::invalid_argument("calibration: the recording has no frame");
  detail::check_per_marker_inputs(model, mapping, options);

  const body::BodyModel start = model;
  SubjectCalibration result;
  result.model = model;
  const double noise_variance = tracker_options.marker_noise_mm * tracker_options.marker_noise_mm;
  detail::BundleAdjustment adjustment(start, mapping, recording, options, noise_variance);
  const std::vector<int>& used = adjustment.used();
  Eigen::VectorXd reference;  // the static trial's reference pose

  for (int round = 0; round <= options.iterations; ++round) {
    const bool last = round == options.iterations;
    if (last && !options.final_pass) break;
    CalibrationPass pass;
    std::vector<detail::BundleFrame> frames = detail::track_pass(
        result.model, mapping, tracker_options, recording, samples, options, pass.mean_marker_distance_mm);
    if (last) {
      result.passes.push_back(pass);
      break;
    }
    if (frames.empty()) throw std::invalid_argument("calibration: no frame could be tracked");
    if (round == 0 && options.static_pose_sd_rad > 0) {
      const std::vector<detail::BundleFrame> still = detail::static_trial_frames(frames, options);
      if (still.empty())
        throw std::invalid_argument("calibration: no frame of the static trial could be tracked");
      reference = detail::choose_static_pose(options, still, model.joint_count(), result.static_pose_choice);
    }

    detail::weigh_static_frames(frames, mapping, recording, used, options);
    // Inliers: observed residuals at the tracked poses within max(floor, 4 x median), the medians
    // counting each residual by its frame's weight (a long static trial's must not set them).
    std::vector<std::vector<double>> distances(frames.size());
    std::vector<double> all, all_weights;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const detail::BundleFrame& frame = frames[k];
      const Eigen::Matrix3Xd predicted = body::marker_positions(
          result.model, body::joint_frames(result.model, frame.position, frame.rotation, frame.joints));
      distances[k].assign(used.size(), -1.0);
      for (std::size_t u = 0; u < used.size(); ++u) {
        const int point = mapping.point_of_marker[static_cast<std::size_t>(used[u])];
        const auto points = recording.frame(frame.index);
        if (point >= points.cols() || !recording.visible(point, frame.index) ||
            !points.col(point).allFinite())
          continue;
        distances[k][u] = (points.col(point) - predicted.col(used[u])).norm();
        all.push_back(distances[k][u]);
        all_weights.push_back(frame.weight);
      }
    }
    const double threshold =
        std::max(options.outlier_floor_mm, 4.0 * detail::weighted_median(all, all_weights));
    // A marker beyond that in most frames sits elsewhere on this subject than the model puts it,
    // which the adjustment corrects, so 4 x its own median is its threshold. (Markers placed by
    // their motion fit the uncalibrated model by construction, lowered the round's median and left
    // Plug-in Gait's PSIS markers out of every frame.)
    std::vector<double> own_threshold(used.size(), threshold);
    for (std::size_t u = 0; u < used.size(); ++u) {
      std::vector<double> own, own_weights;
      for (std::size_t k = 0; k < frames.size(); ++k)
        if (distances[k][u] >= 0) own.push_back(distances[k][u]), own_weights.push_back(frames[k].weight);
      if (const double median = own.empty() ? 0.0 : detail::weighted_median(own, own_weights);
          median > threshold)
        own_threshold[u] = 4.0 * median;
    }
    std::vector<detail::BundleFrame> kept;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      for (std::size_t u = 0; u < used.size(); ++u) {
        if (distances[k][u] < 0) continue;
        if (distances[k][u] > own_threshold[u])
          ++pass.residuals_rejected;
        else
          frames[k].markers.push_back(static_cast<int>(u));
      }
      if (options.static_pose_sd_rad > 0 && detail::in_static_trial(frames[k], options))
        frames[k].prior_joints = reference;
      // A frame's pose is determined only with 3 or more markers.
      if (frames[k].markers.size() >= 3) kept.push_back(std::move(frames[k]));
    }
    if (kept.empty()) throw std::invalid_argument("calibration: no frame shows 3 or more markers");
    detail::hold_static_frames_upright(kept, options);
    pass.frames_used = static_cast<long>(kept.size());
    adjustment.adjust(result.model, kept, pass);
    result.passes.push_back(pass);
    result.marker_residual_rms_mm = detail::marker_residual_rms(result.model, mapping, recording, used, kept);
    if (options.static_pose_sd_rad > 0)
      result.static_posture = detail::mean_joints(detail::static_trial_frames(kept, options));
  }
  result.segment_scale = adjustment.segment_scale();
  result.mean_marker_distance_before_mm = result.passes.front().mean_marker_distance_mm;
  if (options.final_pass) result.mean_marker_distance_after_mm = result.passes.back().mean_marker_distance_mm;
  return result;
}

S2KF_INLINE SubjectCalibration adjust_subject_at_poses(const body::BodyModel& model,
                                                       const body::MarkerMapping& mapping,
                                                       const track::TrackerOptions& tracker_options,
                                                       const MarkerSequence& recording,
                                                       const std::vector<std::pair<long, body::Pose>>& poses,
                                                       const CalibrationOptions& options) {
  options.validate();
  model.validate();
  detail::check_per_marker_inputs(model, mapping, options);
  detail::BundleAdjustment adjustment(model, mapping, recording, options,
                                      tracker_options.marker_noise_mm * tracker_options.marker_noise_mm);
  const std::vector<int>& used = adjustment.used();
  std::vector<detail::BundleFrame> frames =
      detail::frames_at_poses(mapping, recording, used, poses, model.joint_count(),
                              options.static_pose_sd_rad > 0, options.static_pose);
  if (frames.empty()) throw std::invalid_argument("calibration: no posed frame shows 3 or more markers");
  for (detail::BundleFrame& frame : frames)  // a moving trial calibrated with the static one: no prior
    if (!detail::in_static_trial(frame, options)) frame.prior_joints.resize(0);
  detail::hold_static_frames_upright(frames, options);
  detail::weigh_static_frames(frames, mapping, recording, used, options);
  SubjectCalibration result;
  result.model = model;
  CalibrationPass pass;
  pass.frames_used = static_cast<long>(frames.size());
  adjustment.adjust(result.model, frames, pass);
  result.passes.push_back(pass);
  result.marker_residual_rms_mm = detail::marker_residual_rms(result.model, mapping, recording, used, frames);
  if (options.static_pose_sd_rad > 0)
    result.static_posture = detail::mean_joints(detail::static_trial_frames(frames, options));
  result.segment_scale = adjustment.segment_scale();
  result.mean_marker_distance_before_mm = std::numeric_limits<double>::quiet_NaN();
  return result;
}
}  // namespace s2kf::calibration
