/// @file
/// The tracker's chart of the body state and its changes. The state is x = [root position (mm),
/// orientation error delta (rad), Theta (one per joint)]: the root's rotation is R = R_ref Exp(delta)
/// about a reference R_ref the tracker moves after every update, and a joint's angle is
/// theta = (u - l)/2 sin(Theta) + (u + l)/2, the same for Theta, pi - Theta and any 2 pi shift. The
/// tracker keeps each Theta on the principal branch [-pi/2, pi/2]; the smoother undoes the tracker's
/// re-centring between frames with the inverse changes below. Both use these functions only.
#pragma once

#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace s2kf::track {

/// Index of the first Theta in the state (after root position and orientation error).
constexpr int kFirstJointState = 6;

/// The root rotation a state's orientation error stands for: R_ref Exp(delta).
Eigen::Matrix3d chart_rotation(const Eigen::Matrix3d& reference, const Eigen::Vector3d& delta);

/// Flips the sign of state k in a covariance (the state was reflected: Theta -> pi - Theta).
void flip_state_sign(Eigen::MatrixXd& covariance, Eigen::Index k);

/// The constant-velocity state [pose (n), rate of the pose (n)] holds twice the pose's dimension;
/// a pose-only state holds it once. Returns n.
inline Eigen::Index pose_dimension_of(const Eigen::VectorXd& mean, bool with_rates) {
  return with_rates ? mean.size() / 2 : mean.size();
}

/// Moves every Theta of `mean` onto the principal branch [-pi/2, pi/2], where theta(Theta) is
/// one-to-one: first into (-pi, pi], then reflected to +-pi - Theta where needed (the same angle;
/// the sign of that state's covariance row and column flips). With rates (the constant-velocity
/// state), a reflected Theta's rate changes sign too: d(pi - Theta)/dt = -dTheta/dt.
void fold_joint_parameters(Eigen::VectorXd& mean, Eigen::MatrixXd& covariance, bool with_rates = false);

/// Keeps every (folded) Theta where the markers can still move it: its mean at least `margin`
/// inside +-pi/2 and its SD at most `max_sd` (the row and column of the covariance scaled, which
/// keeps it positive definite). At +-pi/2 the slope of theta = mid + half sin(Theta) vanishes, and
/// for a symmetric spread of samples around it the predictions have no linear part in Theta, so a
/// linear-regression filter learns nothing about the joint there and its variance only grows; a
/// Theta spread far beyond pi/2 covers the whole joint range and has no linear part either. Either
/// way the joint would stay at its limit whatever the markers show. With rates, a Theta held at
/// the edge loses a rate that points further out. 0 disables a bound.
void keep_joint_parameters_learnable(Eigen::VectorXd& mean, Eigen::MatrixXd& covariance, double margin,
                                     double max_sd, bool with_rates = false);

/// Expresses the orientation rate (states n+3..n+5 of a state with rates) in a chart whose
/// reference is turned by `turn` (new reference = old reference * turn): a rate about the old
/// reference's axes is turn^T times it about the new ones; its covariance rows and columns follow.
void turn_orientation_rate(Eigen::VectorXd& mean, Eigen::MatrixXd& covariance, const Eigen::Matrix3d& turn);

/// Rewrites a Gaussian of the chart after a re-centring (reference `next`, Theta folded) in the
/// chart before it (reference `previous`, whose Theta values are `previous_mean`): the inverse of
/// the tracker's re-centring, as the smoother needs it.
///
/// Orientation: R_next Exp(e) = R_previous Exp(e') with Exp(e') = D Exp(e), D = R_previous^T R_next,
/// exact for the mean. D is one frame's update, close to the identity, so the covariance is kept as
/// it is (its change is of the order of the angle of D times the error). Joints: of Theta's
/// representatives (Theta + 2k pi, pi - Theta + 2k pi) the one nearest the previous value.
///
/// With rates (the constant-velocity state), the orientation rate turns with the chart (exactly,
/// by D) and a reflected Theta's rate changes sign.
void to_previous_chart(const Eigen::Matrix3d& previous, const Eigen::Matrix3d& next,
                       const Eigen::VectorXd& previous_mean, Eigen::VectorXd& mean,
                       Eigen::MatrixXd& covariance, bool with_rates = false);

}  // namespace s2kf::track

#if !defined(S2KF_COMPILED)
#include <s2kf/track/state_chart.hxx>
#endif
