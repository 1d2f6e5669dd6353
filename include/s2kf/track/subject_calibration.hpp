/// @file
/// Subject calibration: estimating where a subject's markers sit on the segments and how long the
/// subject's bones are, from a recording of that subject, by alternating pose and subject
/// estimation (coordinate descent on the batch least-squares problem over all frames).
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/track/marker_mapping.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracker_options.hpp>
#include <s2kf/track/tracking_metrics.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::track {

struct CalibrationOptions {
  int iterations = 3;                   ///< pose/subject alternations
  bool estimate_segment_scales = true;  ///< re-estimate bone lengths too (else offsets only)
  /// The prior that keeps offsets near the marker set: worth this many frames of data, so a
  /// marker seen in n frames moves by n / (n + k) of what its residuals alone ask for.
  double offset_prior_frames = 20.0;
  /// Relative SD of a segment's length factor around the start, as a prior counted once per frame
  /// used (so it keeps its weight against the data however long the recording): bone lengths and
  /// marker offsets along the bone trade against each other, and a weak prior lets them drift.
  double scale_prior_sd = 0.03;
  long skip_frames = 20;  ///< frames after the tracker starts that are left out (convergence)
  int stride = 2;         ///< every stride-th tracked frame enters the least squares
  /// A residual beyond max(outlier_floor_mm, 4 x the pass's median residual) is left out
  /// (swapped or ghost markers in real recordings).
  double outlier_floor_mm = 30.0;
  /// Per model marker relative weight (e.g. the marker set's `weight` over its noise squared,
  /// scaled to 1 for the tracker's noise); empty: all 1.
  std::vector<double> marker_weight;
  bool final_pass = true;  ///< track once more with the calibrated model to report its distance

  void validate() const {
    if (iterations < 1) throw std::invalid_argument("calibration: at least 1 iteration is needed");
    if (!(offset_prior_frames >= 0))
      throw std::invalid_argument("calibration: the offset prior must be >= 0");
    if (!(scale_prior_sd > 0))
      throw std::invalid_argument("calibration: the scale prior SD must be positive");
    if (skip_frames < 0 || stride < 1)
      throw std::invalid_argument("calibration: skip_frames >= 0 and stride >= 1");
  }
};

/// One tracking pass over the recording with the model of that moment.
struct CalibrationPass {
  double mean_marker_distance_mm = 0;  ///< mean over the frames from skip_frames after the start on
  long frames_used = 0;                ///< frames that entered the least squares (0 for the final pass)
  long residuals_rejected = 0;         ///< marker residuals left out as outliers
};

struct SubjectCalibration {
  body::BodyModel model;                        ///< the calibrated subject (same markers, same order)
  std::map<std::string, double> segment_scale;  ///< bone-length factor per segment, against the input model
  std::vector<CalibrationPass> passes;          ///< pass 0 tracks with the input model
  double mean_marker_distance_before_mm = 0;    ///< pass 0
  double mean_marker_distance_after_mm = 0;     ///< the final pass (or the last pass when there is none)
};

namespace detail {

/// Segments whose outgoing bones can be scaled: every segment that is the parent of a joint with
/// a non-zero translation.
inline std::vector<std::string> scalable_segments(const body::BodyModel& model) {
  std::vector<std::string> segments;
  for (const body::Joint& joint : model.joints) {
    if (joint.translation.norm() == 0) continue;
    const std::string segment = body::segment_of_frame(model, joint.parent_frame);
    if (std::find(segments.begin(), segments.end(), segment) == segments.end()) segments.push_back(segment);
  }
  return segments;
}

struct TrackedFrame {
  long index = 0;
  body::Pose pose;
};

/// Tracks all frames; returns the poses of the frames usable for calibration and the pass's mean
/// marker distance after convergence.
inline std::vector<TrackedFrame> track_pass(const body::BodyModel& model, const MarkerMapping& mapping,
                                            const TrackerOptions& tracker_options, double rate_hz,
                                            const std::vector<Eigen::Matrix3Xd>& points,
                                            const std::vector<Eigen::Array<bool, Eigen::Dynamic, 1>>& visible,
                                            const CalibrationOptions& options, double& mean_distance) {
  Tracker tracker(model, mapping, tracker_options, rate_hz);
  std::vector<double> distance;
  std::vector<TrackedFrame> frames;
  long started = -1;
  for (std::size_t f = 0; f < points.size(); ++f) {
    const FrameEstimate& estimate = tracker.process(points[f], visible[f]);
    distance.push_back(estimate.mean_marker_distance);
    if (!estimate.tracked) continue;
    if (started < 0) started = static_cast<long>(f);
    const long since = static_cast<long>(f) - started;
    if (since >= options.skip_frames && since % options.stride == 0 && estimate.status == FilterStatus::ok)
      frames.push_back({static_cast<long>(f), estimate.pose});
  }
  // Mean over the frames after the convergence allowance (a late spike must not empty the window,
  // as it can with converged_frame).
  mean_distance = mean_from(distance, started < 0 ? 0 : started + options.skip_frames);
  return frames;
}

}  // namespace detail

/// Calibrates `model` (a base model after apply_marker_set, scaled to the subject's height) on a
/// recording: points[f] (3 x P, mm) and visible[f] per frame, `mapping` from recording points to
/// model markers. Each iteration tracks the recording with the current model, then, with those
/// poses fixed, solves the linear least-squares problem in (bone-length factors, marker offsets,
/// one translation per frame) with priors towards the starting model; marker positions are linear
/// in all three when the rotations are fixed, so this is exact Gauss-Newton for that block.
/// Markers the recording never shows keep their offsets. Joint limits are not touched.
inline SubjectCalibration calibrate_subject(const body::BodyModel& model, const MarkerMapping& mapping,
                                            const TrackerOptions& tracker_options, double rate_hz,
                                            const std::vector<Eigen::Matrix3Xd>& points,
                                            const std::vector<Eigen::Array<bool, Eigen::Dynamic, 1>>& visible,
                                            const CalibrationOptions& options = {}) {
  options.validate();
  model.validate();
  if (points.size() != visible.size())
    throw std::invalid_argument("calibration: one visibility vector per frame is needed");
  if (points.empty()) throw std::invalid_argument("calibration: the recording has no frame");
  if (mapping.point_of_marker.size() != static_cast<std::size_t>(model.marker_count()))
    throw std::invalid_argument("calibration: the marker mapping does not fit the body model");
  if (!options.marker_weight.empty() &&
      options.marker_weight.size() != static_cast<std::size_t>(model.marker_count()))
    throw std::invalid_argument("calibration: one weight per model marker is needed");

  const body::BodyModel start = model;
  SubjectCalibration result;
  result.model = model;
  const std::vector<std::string> segments =
      options.estimate_segment_scales ? detail::scalable_segments(model) : std::vector<std::string>{};
  std::vector<double> cumulative(segments.size(), 1.0);
  std::vector<int> used;  // model markers with a recording point
  for (int m = 0; m < model.marker_count(); ++m)
    if (mapping.point_of_marker[static_cast<std::size_t>(m)] >= 0) used.push_back(m);
  const int scale_count = static_cast<int>(segments.size());
  const int unknowns = scale_count + 3 * static_cast<int>(used.size());
  // Which scale each joint's translation belongs to (-1: none).
  std::vector<int> joint_scale(static_cast<std::size_t>(model.joint_count()), -1);
  for (int j = 0; j < model.joint_count(); ++j) {
    const std::string segment =
        body::segment_of_frame(model, model.joints[static_cast<std::size_t>(j)].parent_frame);
    const auto found = std::find(segments.begin(), segments.end(), segment);
    if (found != segments.end())
      joint_scale[static_cast<std::size_t>(j)] = static_cast<int>(found - segments.begin());
  }
  const double noise_variance = tracker_options.marker_noise_mm * tracker_options.marker_noise_mm;

  for (int iteration = 0; iteration <= options.iterations; ++iteration) {
    const bool last = iteration == options.iterations;
    if (last && !options.final_pass) break;
    CalibrationPass pass;
    const std::vector<detail::TrackedFrame> frames =
        detail::track_pass(result.model, mapping, tracker_options, rate_hz, points, visible, options,
                           pass.mean_marker_distance_mm);
    if (last) {
      result.passes.push_back(pass);
      break;
    }
    if (frames.empty()) throw std::invalid_argument("calibration: no frame could be tracked");
    const body::BodyModel& current = result.model;

    // Residuals of every used marker in every frame, for the outlier threshold.
    std::vector<Eigen::Matrix3Xd> residuals;
    std::vector<body::FrameTransforms> transforms;
    std::vector<double> norms;
    for (const detail::TrackedFrame& frame : frames) {
      transforms.push_back(body::joint_frames(current, frame.pose));
      const Eigen::Matrix3Xd predicted = body::marker_positions(current, transforms.back());
      Eigen::Matrix3Xd r = Eigen::Matrix3Xd::Constant(3, static_cast<Eigen::Index>(used.size()),
                                                      std::numeric_limits<double>::quiet_NaN());
      for (std::size_t u = 0; u < used.size(); ++u) {
        const int point = mapping.point_of_marker[static_cast<std::size_t>(used[u])];
        const auto& y = points[static_cast<std::size_t>(frame.index)];
        if (point >= y.cols() || !visible[static_cast<std::size_t>(frame.index)](point) ||
            !y.col(point).allFinite())
          continue;
        r.col(static_cast<Eigen::Index>(u)) = y.col(point) - predicted.col(used[u]);
        norms.push_back(r.col(static_cast<Eigen::Index>(u)).norm());
      }
      residuals.push_back(r);
    }
    const double threshold = std::max(options.outlier_floor_mm, 4.0 * quantile(norms, 0.5));

    // Normal equations of the weighted residuals with each frame's translation eliminated in
    // closed form: sum w (a - mean a)^T (a - mean a) = sum w a^T a - (sum w a)^T (sum w a) / sum w,
    // accumulated block by block (a marker's rows touch the scales and its own offset only).
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(unknowns, unknowns);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(unknowns);
    Eigen::MatrixXd sum_a(3, unknowns);
    Eigen::Matrix3Xd a_scale(3, scale_count);
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const body::FrameTransforms& tf = transforms[k];
      // A frame's translation can only be separated from the subject with 3 or more markers.
      int usable = 0;
      for (std::size_t u = 0; u < used.size(); ++u) {
        const auto r = residuals[k].col(static_cast<Eigen::Index>(u));
        usable += r.allFinite() && r.norm() <= threshold;
      }
      if (usable < 3) continue;
      sum_a.setZero();
      Eigen::Vector3d sum_r = Eigen::Vector3d::Zero();
      double sum_w = 0;
      int count = 0;
      for (std::size_t u = 0; u < used.size(); ++u) {
        const Eigen::Vector3d r = residuals[k].col(static_cast<Eigen::Index>(u));
        if (!r.allFinite()) continue;
        if (r.norm() > threshold) {
          ++pass.residuals_rejected;
          continue;
        }
        const int m = used[u];
        const double w =
            (options.marker_weight.empty() ? 1.0 : options.marker_weight[static_cast<std::size_t>(m)]) /
            noise_variance;
        if (!(w > 0)) continue;
        const int marker_frame = current.markers[static_cast<std::size_t>(m)].frame;
        // d(marker)/d(factor s) = sum of R_parent t_j over the bones of segment s on the chain.
        a_scale.setZero();
        for (int f = marker_frame; f > 0; f = current.joints[static_cast<std::size_t>(f - 1)].parent_frame) {
          const int s = joint_scale[static_cast<std::size_t>(f - 1)];
          if (s < 0) continue;
          const body::Joint& joint = current.joints[static_cast<std::size_t>(f - 1)];
          a_scale.col(s) += tf.rotations[static_cast<std::size_t>(joint.parent_frame)] * joint.translation;
        }
        const Eigen::Matrix3d rotation = tf.rotations[static_cast<std::size_t>(marker_frame)];
        const int at = scale_count + 3 * static_cast<int>(u);
        if (scale_count > 0) {
          normal.topLeftCorner(scale_count, scale_count).noalias() += w * a_scale.transpose() * a_scale;
          normal.block(0, at, scale_count, 3).noalias() += w * a_scale.transpose() * rotation;
          rhs.head(scale_count).noalias() += w * a_scale.transpose() * r;
          sum_a.leftCols(scale_count) += w * a_scale;
        }
        normal.block<3, 3>(at, at).diagonal().array() += w;  // R^T R = I
        rhs.segment<3>(at).noalias() += w * rotation.transpose() * r;
        sum_a.middleCols<3>(at) += w * rotation;
        sum_r += w * r;
        sum_w += w;
        ++count;
      }
      if (count == 0 || !(sum_w > 0)) continue;
      ++pass.frames_used;
      normal.noalias() -= sum_a.transpose() * sum_a / sum_w;
      rhs.noalias() -= sum_a.transpose() * sum_r / sum_w;
    }
    // The scale-offset blocks were filled above the diagonal only.
    normal.triangularView<Eigen::StrictlyLower>() = normal.transpose().triangularView<Eigen::StrictlyLower>();
    if (pass.frames_used == 0) throw std::invalid_argument("calibration: no frame shows 3 or more markers");
    // Priors: offsets near the starting model's, worth offset_prior_frames frames; bone-length
    // factors near 1 with scale_prior_sd.
    for (std::size_t u = 0; u < used.size(); ++u) {
      const int m = used[u];
      const double w =
          (options.marker_weight.empty() ? 1.0 : options.marker_weight[static_cast<std::size_t>(m)]);
      const double lambda = std::max(options.offset_prior_frames * std::max(w, 1e-6), 1e-6) / noise_variance;
      const int at = scale_count + 3 * static_cast<int>(u);
      normal.block<3, 3>(at, at).diagonal().array() += lambda;
      rhs.segment<3>(at) -= lambda * (current.markers[static_cast<std::size_t>(m)].offset -
                                      start.markers[static_cast<std::size_t>(m)].offset);
    }
    const double scale_lambda =
        static_cast<double>(pass.frames_used) / (options.scale_prior_sd * options.scale_prior_sd);
    for (int s = 0; s < scale_count; ++s) {
      const double c = cumulative[static_cast<std::size_t>(s)];
      normal(s, s) += scale_lambda * c * c;
      rhs(s) -= scale_lambda * c * (c - 1.0);
    }
    const Eigen::VectorXd step = normal.ldlt().solve(rhs);
    if (!step.allFinite())
      throw std::runtime_error("calibration: the least-squares system could not be solved");
    body::BodyModel updated = current;
    for (int j = 0; j < updated.joint_count(); ++j) {
      const int s = joint_scale[static_cast<std::size_t>(j)];
      if (s >= 0) updated.joints[static_cast<std::size_t>(j)].translation *= 1.0 + step(s);
    }
    for (int s = 0; s < scale_count; ++s) cumulative[static_cast<std::size_t>(s)] *= 1.0 + step(s);
    for (std::size_t u = 0; u < used.size(); ++u)
      updated.markers[static_cast<std::size_t>(used[u])].offset +=
          step.segment<3>(scale_count + 3 * static_cast<int>(u));
    result.model = updated;
    result.passes.push_back(pass);
  }
  for (int s = 0; s < scale_count; ++s)
    result.segment_scale[segments[static_cast<std::size_t>(s)]] = cumulative[static_cast<std::size_t>(s)];
  result.mean_marker_distance_before_mm = result.passes.front().mean_marker_distance_mm;
  result.mean_marker_distance_after_mm = result.passes.back().mean_marker_distance_mm;
  return result;
}

}  // namespace s2kf::track
