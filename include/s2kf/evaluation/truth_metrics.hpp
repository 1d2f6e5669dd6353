/// @file
/// Accuracy of an estimated motion against ground truth (docs/results.md defines the metrics):
/// segment-orientation error, limb flexion error, all-joint error and worst joint, root errors, joint-limit
/// violations.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/io/motion_files.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::evaluation {

struct TruthComparison {
  long frames = 0;  ///< frames compared (after the warm-up, both finite)
  double segment_orientation_rms_deg = 0;
  double limb_flexion_rms_deg = 0;  ///< Sx, Ex, Hx, Kx, Ax of both sides
  double all_joint_rms_deg = 0;
  std::string worst_joint;
  double worst_joint_rms_deg = 0;
  double root_position_rms_mm = 0;
  double root_orientation_rms_deg = 0;
  long joint_limit_violations = 0;              ///< estimated angles outside the model's limits (all frames)
  std::vector<double> per_frame_joint_rms_deg;  ///< all-joint RMS per compared frame (NaN when skipped)
  std::vector<std::pair<std::string, double>> segment_rms_deg;  ///< per segment (named by its frame)
};

inline body::Pose pose_of_row(const io::MotionTable& motion, Eigen::Index row) {
  return body::pose_from_row(motion.values.row(row).transpose());
}

/// Compares frame by frame (rows with the same index) from `warmup` on. The joint columns of both
/// tables must match the model's joints. Segments are the frames markers ride on.
TruthComparison compare_with_truth(const body::BodyModel& model, const io::MotionTable& estimate,
                                   const io::MotionTable& truth, long warmup);

}  // namespace s2kf::evaluation

#if !defined(S2KF_COMPILED)
#include <s2kf/evaluation/truth_metrics.hxx>
#endif
