/// @file
/// The definitions of <s2kf/track/state_chart.hpp>: inline where the library is used header-only, compiled
/// once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/track/state_chart.hpp>

namespace s2kf::track {

S2KF_INLINE Eigen::Matrix3d chart_rotation(const Eigen::Matrix3d& reference, const Eigen::Vector3d& delta) {
  return reference * body::rotation_exp(delta);
}

S2KF_INLINE void flip_state_sign(Eigen::MatrixXd& covariance, Eigen::Index k) {
  covariance.row(k) *= -1;
  covariance.col(k) *= -1;
}

S2KF_INLINE void fold_joint_parameters(Eigen::VectorXd& mean, Eigen::MatrixXd& covariance, bool with_rates) {
  const Eigen::Index n = pose_dimension_of(mean, with_rates);
  for (Eigen::Index k = kFirstJointState; k < n; ++k) {
    const double folded = std::remainder(mean(k), 2 * kPi);  // (-pi, pi]
    mean(k) = folded;
    if (std::abs(folded) > kPi / 2) {
      mean(k) = (folded > 0 ? kPi : -kPi) - folded;
      flip_state_sign(covariance, k);
      if (with_rates) {
        mean(n + k) = -mean(n + k);
        flip_state_sign(covariance, n + k);
      }
    }
  }
}

S2KF_INLINE void keep_joint_parameters_learnable(Eigen::VectorXd& mean, Eigen::MatrixXd& covariance,
                                                 double margin, double max_sd, bool with_rates) {
  const Eigen::Index n = pose_dimension_of(mean, with_rates);
  const double edge = kPi / 2 - margin;
  for (Eigen::Index k = kFirstJointState; k < n; ++k) {
    if (margin > 0 && std::abs(mean(k)) > edge) {
      // Held at the edge: a rate that would carry it further out is spent against the limit.
      if (with_rates && mean(n + k) * mean(k) > 0) mean(n + k) = 0;
      mean(k) = std::clamp(mean(k), -edge, edge);
    }
    if (max_sd > 0 && covariance(k, k) > max_sd * max_sd) {
      const double scale = max_sd / std::sqrt(covariance(k, k));
      covariance.row(k) *= scale;
      covariance.col(k) *= scale;
    }
  }
}

S2KF_INLINE void turn_orientation_rate(Eigen::VectorXd& mean, Eigen::MatrixXd& covariance,
                                       const Eigen::Matrix3d& turn) {
  const Eigen::Index r = mean.size() / 2 + 3;
  const Eigen::Matrix3d t = turn.transpose();
  mean.segment<3>(r) = (t * mean.segment<3>(r)).eval();
  covariance.middleRows<3>(r) = (t * covariance.middleRows<3>(r)).eval();
  covariance.middleCols<3>(r) = (covariance.middleCols<3>(r) * turn).eval();
}

S2KF_INLINE void to_previous_chart(const Eigen::Matrix3d& previous, const Eigen::Matrix3d& next,
                                   const Eigen::VectorXd& previous_mean, Eigen::VectorXd& mean,
                                   Eigen::MatrixXd& covariance, bool with_rates) {
  const Eigen::Matrix3d d = previous.transpose() * next;
  mean.segment<3>(3) = body::rotation_log(d * body::rotation_exp(mean.segment<3>(3)));
  const Eigen::Index n = pose_dimension_of(mean, with_rates);
  if (with_rates) turn_orientation_rate(mean, covariance, d.transpose());
  for (Eigen::Index k = kFirstJointState; k < n; ++k) {
    const double reference = previous_mean(k);
    const auto nearest = [&](double value) {
      return value + 2 * kPi * std::round((reference - value) / (2 * kPi));
    };
    const double direct = nearest(mean(k)), reflected = nearest(kPi - mean(k));
    if (std::abs(reflected - reference) < std::abs(direct - reference)) {
      mean(k) = reflected;
      flip_state_sign(covariance, k);
      if (with_rates) {
        mean(n + k) = -mean(n + k);
        flip_state_sign(covariance, n + k);
      }
    } else {
      mean(k) = direct;
    }
  }
}

}  // namespace s2kf::track
