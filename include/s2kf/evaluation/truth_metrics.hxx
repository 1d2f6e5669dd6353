/// @file
/// The definitions of <s2kf/evaluation/truth_metrics.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/evaluation/truth_metrics.hpp>

namespace s2kf::evaluation {
S2KF_INLINE TruthComparison compare_with_truth(const body::BodyModel& model, const io::MotionTable& estimate,
                                               const io::MotionTable& truth, long warmup) {
  if (estimate.joint_names != model.joint_names() || truth.joint_names != model.joint_names())
    throw std::invalid_argument("compare_with_truth: joint columns differ from the body model's");
  std::set<int> segment_frames;
  for (const body::Marker& marker : model.markers) segment_frames.insert(marker.frame);
  const double degrees = kDegreesPerRadian;
  auto angle_between = [](const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    return Eigen::AngleAxisd(a.transpose() * b).angle();
  };
  TruthComparison result;
  const Eigen::Index rows = std::min(estimate.frames(), truth.frames());
  const int nj = model.joint_count();
  Eigen::VectorXd joint_sq = Eigen::VectorXd::Zero(nj);
  Eigen::VectorXd joint_n = Eigen::VectorXd::Zero(nj);  // joints not observed (NaN) are left out
  double segment_sq = 0, root_position_sq = 0, root_orientation_sq = 0;
  std::vector<double> per_segment_sq(model.frame_count(), 0.0);
  std::vector<long> per_segment_n(model.frame_count(), 0);
  long segment_count = 0;
  for (Eigen::Index r = 0; r < rows; ++r) {
    const body::Pose est = pose_of_row(estimate, r);
    if (est.joints.allFinite())
      for (int j = 0; j < nj; ++j)
        if (est.joints(j) < model.joints[j].lower - 1e-9 || est.joints(j) > model.joints[j].upper + 1e-9)
          ++result.joint_limit_violations;
    result.per_frame_joint_rms_deg.push_back(std::numeric_limits<double>::quiet_NaN());
    if (r < warmup || !io::is_tracked_row(estimate.values.row(r).transpose()) ||
        !truth.values.row(r).allFinite())
      continue;
    const body::Pose tru = pose_of_row(truth, r);
    const Eigen::ArrayXd diff = (est.joints - tru.joints).array();
    const Eigen::ArrayXd observed = diff.isFinite().cast<double>();
    const Eigen::ArrayXd squared = observed.select(diff.square(), 0.0);
    joint_sq += squared.matrix();
    joint_n += observed.matrix();
    result.per_frame_joint_rms_deg.back() = std::sqrt(squared.sum() / observed.sum()) * degrees;
    const body::FrameTransforms fe = body::joint_frames(model, est), ft = body::joint_frames(model, tru);
    for (int f : segment_frames) {
      const double sq = std::pow(angle_between(fe.rotations[f], ft.rotations[f]), 2);
      if (!std::isfinite(sq)) continue;  // beyond a joint that is not observed
      segment_sq += sq;
      per_segment_sq[f] += sq;
      ++per_segment_n[f];
      ++segment_count;
    }
    root_position_sq += (est.root_position - tru.root_position).squaredNorm();
    root_orientation_sq += std::pow(angle_between(est.root_rotation(), tru.root_rotation()), 2);
    ++result.frames;
  }
  if (result.frames == 0) return result;
  const double n = static_cast<double>(result.frames);
  result.segment_orientation_rms_deg = std::sqrt(segment_sq / static_cast<double>(segment_count)) * degrees;
  result.all_joint_rms_deg = std::sqrt(joint_sq.sum() / joint_n.sum()) * degrees;
  result.root_position_rms_mm = std::sqrt(root_position_sq / n);
  result.root_orientation_rms_deg = std::sqrt(root_orientation_sq / n) * degrees;
  double limb_sq = 0;
  double limb_count = 0;
  for (int j = 0; j < nj; ++j) {
    if (joint_n(j) == 0) continue;
    const double rms = std::sqrt(joint_sq(j) / joint_n(j)) * degrees;
    if (rms > result.worst_joint_rms_deg)
      result.worst_joint_rms_deg = rms, result.worst_joint = model.joints[j].name;
    const std::string& name = model.joints[j].name;
    if (body::is_limb_flexion(name)) limb_sq += joint_sq(j), limb_count += joint_n(j);
  }
  result.limb_flexion_rms_deg = std::sqrt(limb_sq / limb_count) * degrees;
  for (int f : segment_frames)
    if (per_segment_n[f] > 0)
      result.segment_rms_deg.emplace_back(
          model.frame_name(f),
          std::sqrt(per_segment_sq[f] / static_cast<double>(per_segment_n[f])) * degrees);
  return result;
}
}  // namespace s2kf::evaluation
