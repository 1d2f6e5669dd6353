/// @file
/// How well a recording determines a subject: the bundle adjustment's information about the
/// subject's unknowns (bone-length factors and marker offsets) from the data at known poses, the
/// poses eliminated, in the priors' metric. Below the calibration's prior_only_fraction threshold a
/// direction is left to the priors; the identifiable-subject reference (evaluation/) resets it.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/marker_sequence.hpp>

#include <Eigen/Core>

#include <string>
#include <utility>
#include <vector>

namespace s2kf::calibration {

struct SubjectInformation {
  /// The segments with a length factor, in the order of the unknowns; the offsets (3 per mapped
  /// marker, in the model's marker order) follow them.
  std::vector<std::string> segments;
  /// The data's information about the unknowns divided by their prior SDs: an eigenvalue is the
  /// ratio of the data's information to the prior's along its eigenvector.
  Eigen::MatrixXd information;
  Eigen::VectorXd prior_sd;  ///< each unknown's prior SD (the metric's scale)
  double threshold =
      0;  ///< the ratio below which options.prior_only_fraction leaves a direction to the prior
  long frames_used = 0;  ///< poses whose frame shows 3 or more mapped markers
};

/// The information about a subject that starts as `start` (its scalable segments and mapped
/// markers set the unknowns, as calibrate_subject does) from `recording` at the known `poses`,
/// linearised at `model` (e.g. the true subject), with the marker weights and priors of `options`,
/// the marker noise variance `noise_variance` (mm^2) and the threshold of `prior_only_fraction`.
/// Throws std::invalid_argument for a pose outside the recording or with another joint count.
SubjectInformation subject_information(const body::BodyModel& start, const body::BodyModel& model,
                                       const body::MarkerMapping& mapping, const MarkerSequence& recording,
                                       const std::vector<std::pair<long, body::Pose>>& poses,
                                       const CalibrationOptions& options, double noise_variance,
                                       double prior_only_fraction);

}  // namespace s2kf::calibration

#if !defined(S2KF_COMPILED)
#include <s2kf/calibration/subject_information.hxx>
#endif
