/// @file
/// The definitions of <s2kf/body/marker_measurement_model.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/body/marker_measurement_model.hpp>

namespace s2kf::body {

S2KF_INLINE Eigen::MatrixXd marker_noise(double variance_mm2, Eigen::Index marker_count) {
  if (!(variance_mm2 >= 0) || !std::isfinite(variance_mm2) || marker_count < 0)
    throw std::invalid_argument("marker_noise: the variance must be a finite number >= 0 (mm^2)");
  return Eigen::VectorXd::Constant(3 * marker_count, variance_mm2).asDiagonal();
}

S2KF_INLINE Eigen::MatrixXd marker_noise(const Eigen::Ref<const Eigen::VectorXd>& variance_mm2_per_marker) {
  if (!variance_mm2_per_marker.allFinite() || (variance_mm2_per_marker.array() < 0).any())
    throw std::invalid_argument("marker_noise: every variance must be a finite number >= 0 (mm^2)");
  Eigen::VectorXd diagonal(3 * variance_mm2_per_marker.size());
  for (Eigen::Index m = 0; m < variance_mm2_per_marker.size(); ++m)
    diagonal.segment<3>(3 * m).setConstant(variance_mm2_per_marker(m));
  return diagonal.asDiagonal();
}

S2KF_INLINE Pose MarkerMeasurementModel::pose(const Eigen::Ref<const Eigen::VectorXd>& state) const {
  check_state_size(state.size(), "pose");
  const Eigen::Vector3d rpy = orientation_ == OrientationParameterization::roll_pitch_yaw
                                  ? Eigen::Vector3d(state.segment<3>(3))
                                  : rpy_from_rotation(root_rotation(state.segment<3>(3)));
  return Pose{state.head<3>(), rpy, joints_.angles(state.tail(model_.joint_count()))};
}

S2KF_INLINE Eigen::VectorXd MarkerMeasurementModel::state(const Pose& pose) const {
  detail::check_joint_count(model_, pose.joints.size(), "MarkerMeasurementModel::state");
  Eigen::VectorXd x(state_dimension());
  x.head<3>() = pose.root_position;
  x.segment<3>(3) = orientation_ == OrientationParameterization::roll_pitch_yaw
                        ? pose.root_rpy
                        : rotation_log(reference_.transpose() * pose.root_rotation());
  x.tail(model_.joint_count()) = joints_.parameters(pose.joints);
  return x;
}

S2KF_INLINE void MarkerMeasurementModel::operator()(const Eigen::Ref<const Eigen::MatrixXd>& states,
                                                    Eigen::Ref<Eigen::MatrixXd> predictions) {
  const Eigen::Index count = states.cols();
  check_state_size(states.rows(), "operator()");
  check_predictions_size(predictions, count);
  if (single_precision_)
    evaluate(states, predictions, ws_single_, orientation_single_);
  else
    evaluate(states, predictions, ws_, orientation_buffer_);
}

S2KF_INLINE void MarkerMeasurementModel::evaluate_symmetric(
    const Eigen::Ref<const Eigen::MatrixXd>& states, const Eigen::Ref<const Eigen::VectorXd>& mean,
    const Eigen::Ref<const Eigen::MatrixXd>& half_deviations, Eigen::Index origin_count,
    Eigen::Ref<Eigen::MatrixXd> predictions) {
  const Eigen::Index count = states.cols();
  if (!single_precision_deviations_ || single_precision_ || half_deviations.cols() == 0) {
    (*this)(states, predictions);
    return;
  }
  check_state_size(states.rows(), "evaluate_symmetric");
  if (mean.size() != states.rows() || half_deviations.rows() != states.rows() || origin_count < 0 ||
      origin_count + 2 * half_deviations.cols() != count)
    throw DimensionError(
        "MarkerMeasurementModel::evaluate_symmetric: the mean and the half deviations do not "
        "describe the " +
        std::to_string(count) + " samples");
  check_predictions_size(predictions, count);
  evaluate_deviations<double, double>(mean, half_deviations, origin_count, predictions.data(),
                                      predictions.outerStride(), count);
}

S2KF_INLINE bool MarkerMeasurementModel::evaluate_symmetric_deviations(
    const Eigen::Ref<const Eigen::VectorXd>& mean, const Eigen::Ref<const Eigen::MatrixXf>& half_deviations,
    Eigen::Index origin_count, Eigen::Ref<Eigen::MatrixXf> deviations,
    Eigen::Ref<Eigen::VectorXd> mean_prediction) {
  if (!single_precision_deviations_ || single_precision_ || half_deviations.cols() == 0) return false;
  check_state_size(mean.size(), "evaluate_symmetric_deviations");
  const Eigen::Index count = deviations.cols();
  if (half_deviations.rows() != mean.size() || origin_count < 0 ||
      origin_count + 2 * half_deviations.cols() != count || deviations.rows() != measurement_dimension() ||
      mean_prediction.size() != measurement_dimension())
    throw DimensionError(
        "MarkerMeasurementModel::evaluate_symmetric_deviations: the half deviations, the deviations and "
        "the mean prediction do not fit the mean and the model");
  eigen_assert(deviations.innerStride() == 1);
  evaluate_deviations<float, float>(mean, half_deviations, origin_count, deviations.data(),
                                    deviations.outerStride(), count);
  mean_prediction = mean_prediction_;
  return true;
}

}  // namespace s2kf::body
