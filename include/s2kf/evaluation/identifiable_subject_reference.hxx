/// @file
/// The definitions of <s2kf/evaluation/identifiable_subject_reference.hpp>: inline where the library is used
/// header-only, compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/evaluation/identifiable_subject_reference.hpp>

#include <s2kf/calibration/subject_information.hpp>

namespace s2kf::evaluation {
S2KF_INLINE IdentifiableSubject identifiable_subject(const body::BodyModel& nominal,
                                                     const sim::Subject& subject,
                                                     const sim::Recording& recording,
                                                     const std::vector<long>& frames,
                                                     const calibration::CalibrationOptions& options,
                                                     double marker_noise_mm, double prior_only_fraction) {
  const body::BodyModel& truth = subject.model;
  if (nominal.marker_names() != truth.marker_names() || nominal.joint_names() != truth.joint_names())
    throw std::invalid_argument(
        "identifiable_subject: the nominal model has other joints or markers than the subject");
  if (recording.labels != subject.marker_names ||
      recording.truth.size() != static_cast<std::size_t>(recording.frames()))
    throw std::invalid_argument("identifiable_subject: the recording was not simulated on this subject");
  if (!(marker_noise_mm > 0) || !(prior_only_fraction >= 0))
    throw std::invalid_argument(
        "identifiable_subject: the marker noise must be positive, the threshold >= 0");
  options.validate();
  body::MarkerMapping mapping;
  for (int m = 0; m < truth.marker_count(); ++m) mapping.point_of_marker.push_back(m);
  // The calibration frames at their true poses.
  std::vector<std::pair<long, body::Pose>> poses;
  for (long k : frames) {
    if (k < 0 || k >= recording.frames())
      throw std::invalid_argument("identifiable_subject: a calibration frame lies outside the recording");
    poses.emplace_back(k, recording.truth[static_cast<std::size_t>(k)]);
  }
  const calibration::SubjectInformation information =
      calibration::subject_information(nominal, truth, mapping, recording, poses, options,
                                       marker_noise_mm * marker_noise_mm, prior_only_fraction);
  if (information.frames_used == 0)
    throw std::invalid_argument("identifiable_subject: no calibration frame shows 3 markers");

  // The nominal in the adjustment's unknowns at the true subject: length factors (nominal bone
  // over true bone, least squares over the segment's bones, minus 1) and offsets (nominal - true).
  const std::vector<std::string>& segments = information.segments;
  const int scales = static_cast<int>(segments.size());
  Eigen::VectorXd nominal_step(scales + 3 * truth.marker_count());
  for (int s = 0; s < scales; ++s) {
    double cross = 0, square = 0;
    for (std::size_t j = 0; j < truth.joints.size(); ++j)
      if (body::segment_of_frame(truth, truth.joints[j].parent_frame) ==
          segments[static_cast<std::size_t>(s)]) {
        cross += nominal.joints[j].translation.dot(truth.joints[j].translation);
        square += truth.joints[j].translation.squaredNorm();
      }
    nominal_step(s) = cross / square - 1.0;
  }
  for (int m = 0; m < truth.marker_count(); ++m)
    nominal_step.segment<3>(scales + 3 * m) = nominal.markers[static_cast<std::size_t>(m)].offset -
                                              truth.markers[static_cast<std::size_t>(m)].offset;

  // Reset: the part of that step along the undetermined eigenvectors, in the priors' metric.
  const Eigen::VectorXd& prior_sd = information.prior_sd;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(information.information);
  if (eigen.info() != Eigen::Success)
    throw std::runtime_error("identifiable_subject: the eigen-decomposition did not converge");
  const Eigen::VectorXd whitened_step = nominal_step.cwiseQuotient(prior_sd);
  Eigen::VectorXd reset = Eigen::VectorXd::Zero(whitened_step.size());
  IdentifiableSubject result;
  result.information_ratios = eigen.eigenvalues();
  result.frames_used = information.frames_used;
  result.threshold = information.threshold;
  for (Eigen::Index i = 0; i < eigen.eigenvalues().size(); ++i) {
    if (eigen.eigenvalues()(i) >= result.threshold) continue;
    const auto v = eigen.eigenvectors().col(i);
    reset += v * v.dot(whitened_step);
    ++result.reset_directions;
  }
  reset = reset.cwiseProduct(prior_sd);

  result.model = truth;
  for (std::size_t j = 0; j < result.model.joints.size(); ++j) {
    const std::string segment = body::segment_of_frame(truth, truth.joints[j].parent_frame);
    for (int s = 0; s < scales; ++s)
      if (segments[static_cast<std::size_t>(s)] == segment)
        result.model.joints[j].translation *= 1.0 + reset(s);
  }
  for (int m = 0; m < truth.marker_count(); ++m)
    result.model.markers[static_cast<std::size_t>(m)].offset += reset.segment<3>(scales + 3 * m);
  return result;
}
}  // namespace s2kf::evaluation
