/// @file
/// The definitions of <s2kf/track/tracker.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/track/tracker.hpp>

namespace s2kf::track {
S2KF_INLINE Tracker::Tracker(body::BodyModel model, body::MarkerMapping mapping, TrackerOptions options,
                             double rate_hz, const SampleSet& samples)
    : model_(std::move(model)),
      mapping_(std::move(mapping)),
      options_(validated(std::move(options), rate_hz)),
      rate_hz_(rate_hz),
      filter_(checked(samples, kRootDofs + model_.joint_count())),
      measurement_model_(model_, body::OrientationParameterization::local_rotation_error) {
  if (mapping_.point_of_marker.size() != static_cast<std::size_t>(model_.marker_count()))
    throw std::invalid_argument("the marker mapping does not fit the body model");
  for (int m = 0; m < model_.marker_count(); ++m)
    if (mapping_.point_of_marker[m] >= 0) used_markers_.push_back(m);
  if (used_markers_.empty()) throw std::invalid_argument("no recording label matches a marker of the model");
  // The measurement stacks the markers body part by body part (model order within a part), so
  // the information form's groups are consecutive.
  std::vector<int> part_of_marker(static_cast<std::size_t>(model_.marker_count()));
  for (int m = 0; m < model_.marker_count(); ++m)
    part_of_marker[static_cast<std::size_t>(m)] =
        body_part_of_frame(model_, model_.markers[static_cast<std::size_t>(m)].frame);
  std::stable_sort(used_markers_.begin(), used_markers_.end(), [&](int a, int b) {
    return part_of_marker[static_cast<std::size_t>(a)] < part_of_marker[static_cast<std::size_t>(b)];
  });
  for (const int m : used_markers_)
    information_groups_.insert(information_groups_.end(), 3, part_of_marker[static_cast<std::size_t>(m)]);
  // Each marker reads the root's pose and the joints from the root to its segment.
  for (const int m : used_markers_) {
    std::vector<int> states(kRootDofs);
    for (int k = 0; k < kRootDofs; ++k) states[static_cast<std::size_t>(k)] = k;
    for (int frame = model_.markers[static_cast<std::size_t>(m)].frame; frame > 0;
         frame = model_.joints[static_cast<std::size_t>(frame - 1)].parent_frame)
      states.push_back(kRootDofs + frame - 1);
    marker_dependencies_.push_back(std::move(states));
  }
  measurement_model_.select_markers(used_markers_);
  measurement_model_.set_single_precision(options_.single_precision_kinematics);  // not the reported markers
  measurement_model_.set_single_precision_deviations(options_.single_precision_kinematic_deviations);
  const int n = state_dimension();
  const double dt = 1.0 / rate_hz_;
  const int d = motion_state_dimension();
  process_noise_ = Eigen::MatrixXd::Zero(d, d);
  process_noise_.diagonal().segment<3>(0).setConstant(std::pow(options_.position_speed_mm_per_s * dt, 2));
  process_noise_.diagonal().segment<3>(3).setConstant(std::pow(options_.orientation_speed_rad_per_s * dt, 2));
  for (int j = 0; j < joint_count(); ++j) {
    const bool flexion = body::is_limb_flexion(model_.joints[static_cast<std::size_t>(j)].name);
    const double speed = flexion ? options_.flexion_speed_per_s : options_.joint_speed_per_s;
    process_noise_(kRootDofs + j, kRootDofs + j) = std::pow(speed * dt, 2);
  }
  transition_ = Eigen::MatrixXd::Identity(d, d);
  if (with_rates()) {
    // White-noise acceleration of spectral density q per component: the exact
    // discretisation of x' = v, v' = a over dt.
    transition_.topRightCorner(n, n).diagonal().setConstant(dt);
    for (int k = 0; k < n; ++k) {
      const double a = k < 3           ? options_.position_acceleration
                       : k < kRootDofs ? options_.orientation_acceleration
                                       : options_.joint_acceleration;
      const double q = a * a;
      process_noise_(k, k) += q * dt * dt * dt / 3;
      process_noise_(k, n + k) = process_noise_(n + k, k) = q * dt * dt / 2;
      process_noise_(n + k, n + k) = q * dt;
    }
  }
  const Eigen::Index m = 3 * static_cast<Eigen::Index>(used_markers_.size());
  if (!options_.marker_noise_mm_per_marker.empty() &&
      options_.marker_noise_mm_per_marker.size() != static_cast<std::size_t>(model_.marker_count()))
    throw std::invalid_argument("one marker noise per model marker is needed (or none)");
  noise_ = Eigen::MatrixXd::Zero(m, m);
  for (std::size_t k = 0; k < used_markers_.size(); ++k) {
    double sd = options_.marker_noise_mm;
    if (!options_.marker_noise_mm_per_marker.empty() &&
        !std::isnan(options_.marker_noise_mm_per_marker[static_cast<std::size_t>(used_markers_[k])]))
      sd = options_.marker_noise_mm_per_marker[static_cast<std::size_t>(used_markers_[k])];
    noise_.diagonal().segment<3>(3 * static_cast<Eigen::Index>(k)).setConstant(sd * sd);
  }
  measurement_ = Eigen::VectorXd::Constant(m, std::numeric_limits<double>::quiet_NaN());
  observed_.resize(m);
  repeat_frames_.assign(used_markers_.size(), 0);
  frozen_frames_ = static_cast<int>(std::ceil(options_.frozen_marker_s * rate_hz_));
  estimate_.rejection.assign(static_cast<std::size_t>(model_.marker_count()), MarkerRejection::none);
  if (options_.axial_split_sd_rad > 0) {
    const std::vector<std::string> names = model_.joint_names();
    const auto find = [&](const char* name) {
      const auto at = std::find(names.begin(), names.end(), name);
      return at == names.end() ? -1 : static_cast<int>(at - names.begin());
    };
    for (const auto& [a, b] : {std::pair{"BPz", "BTz"}, std::pair{"BLNz", "BUNz"}})
      if (find(a) >= 0 && find(b) >= 0) axial_pairs_.emplace_back(find(a), find(b));
    axial_gain_.resize(n);
    axial_column_.resize(n);
  }
  estimate_.marker_distance.resize(model_.marker_count());
}

S2KF_INLINE const FrameEstimate& Tracker::process(const Eigen::Matrix3Xd& points,
                                                  const Eigen::Array<bool, Eigen::Dynamic, 1>& visible) {
  const auto start = std::chrono::steady_clock::now();
  if (points.cols() != visible.size())
    throw std::invalid_argument("process: one visibility flag per recording point is needed");
  int count = 0, repeated = 0;
  std::fill(estimate_.rejection.begin(), estimate_.rejection.end(), MarkerRejection::none);
  estimate_.rejected_markers = 0;
  for (std::size_t k = 0; k < used_markers_.size(); ++k) {
    const int point = mapping_.point_of_marker[used_markers_[k]];
    const bool seen = point < points.cols() && visible(point) && points.col(point).allFinite();
    const bool same = seen && (measurement_.segment<3>(3 * k).array() == points.col(point).array()).all();
    repeat_frames_[k] = same ? repeat_frames_[k] + 1 : 0;
    for (int a = 0; a < 3; ++a) {
      observed_(3 * k + a) = seen;
      measurement_(3 * k + a) = seen ? points(a, point) : 0.0;
    }
    count += seen;
    repeated += same;
  }
  estimate_.visible_markers = count;
  // A stuck marker repeats its coordinates exactly; when most of the others
  // moved this frame, a marker that has repeated for frozen_marker_s is left
  // out (until it moves again).
  if (frozen_frames_ > 0 && 2 * repeated < count)
    for (std::size_t k = 0; k < used_markers_.size(); ++k)
      if (repeat_frames_[k] >= frozen_frames_) {
        observed_.segment<3>(3 * static_cast<Eigen::Index>(k)).setConstant(false);
        estimate_.rejection[static_cast<std::size_t>(used_markers_[k])] = MarkerRejection::frozen;
        ++estimate_.rejected_markers;
        --count;
      }
  ++frames_;
  if (!initialised_) {
    if (count >= options_.min_markers_to_start) initialise(points);
    if (!initialised_) {
      estimate_.tracked = false;
      estimate_.status = FilterStatus::nothing_observed;
      finish(points, visible, start);
      return estimate_;
    }
  } else if (with_rates()) {
    predict_constant_velocity();
  } else {
    filter_.predict_random_walk(state_, process_noise_);
  }
  UpdateOptions update_options;
  update_options.gate_probability = options_.gate_probability;
  if (frames_since_start_ <= options_.converging_frames)
    update_options.iterations =
        frames_since_start_ == 0 ? options_.initial_iterations : options_.converging_iterations;
  else
    update_options.block_gate_probability = options_.marker_gate_probability;  // once converged
  update_options.block_size = 3;
  update_options.single_precision_moments = options_.single_precision_moments;
  update_options.information_form = options_.information_form_update;
  update_options.information_form_max_nonlinearity = options_.information_form_max_nonlinearity;
  update_options.information_groups = &information_groups_;
  if (options_.information_form_root_products)
    update_options.information_quadratic_states = &root_orientation_states_;
  if (options_.marker_dependencies) update_options.block_dependencies = &marker_dependencies_;
  ++frames_since_start_;
  estimate_.status = FilterStatus::nothing_observed;
  estimate_.nis = std::numeric_limits<double>::quiet_NaN();
  if (count > 0) {
    measurement_model_.set_reference_orientation(reference_rotation_);
    const UpdateResult result =
        filter_.update(state_, measurement_model_, measurement_, noise_, observed_, update_options);
    estimate_.status = result.status;
    estimate_.nis = result.nis;
    for (const Eigen::Index block : filter_.rejected_blocks()) {
      estimate_.rejection[static_cast<std::size_t>(used_markers_[static_cast<std::size_t>(block)])] =
          MarkerRejection::innovation;
      ++estimate_.rejected_markers;
    }
    if (result.ok()) {
      // After the markers' update: the split of the unseen twists, the rates conditioned on the
      // new pose, then re-centring, which folds what they moved (the orientation error among
      // them) into the reference.
      split_axial_twists();
      if (with_rates()) condition_rates();
      recentre();
    }
  }
  estimate_.tracked = true;
  finish(points, visible, start);
  return estimate_;
}

S2KF_INLINE void Tracker::split_axial_twists() {
  const double variance = options_.axial_split_sd_rad * options_.axial_split_sd_rad;
  for (const auto& [a, b] : axial_pairs_) {
    const Eigen::Index ia = kRootDofs + a, ib = kRootDofs + b;
    const body::Joint& ja = model_.joints[static_cast<std::size_t>(a)];
    const body::Joint& jb = model_.joints[static_cast<std::size_t>(b)];
    const double half_a = 0.5 * (ja.upper - ja.lower), half_b = 0.5 * (jb.upper - jb.lower);
    const double ta = state_.mean(ia), tb = state_.mean(ib);
    // theta = mid + half sin(Theta): h = theta_a - theta_b, H = [half_a cos
    // Theta_a, -half_b cos Theta_b].
    const double ha = half_a * std::cos(ta), hb = -half_b * std::cos(tb);
    const double residual = -(0.5 * (ja.upper + ja.lower) + half_a * std::sin(ta) -
                              0.5 * (jb.upper + jb.lower) - half_b * std::sin(tb));
    axial_column_.noalias() = ha * state_.covariance.col(ia) + hb * state_.covariance.col(ib);  // C H^T
    const double innovation_variance = ha * axial_column_(ia) + hb * axial_column_(ib) + variance;
    axial_gain_ = axial_column_ / innovation_variance;
    state_.mean.noalias() += residual * axial_gain_;
    state_.covariance.noalias() -= axial_gain_ * axial_column_.transpose();
  }
}

S2KF_INLINE void Tracker::initialise(const Eigen::Matrix3Xd& points) {
  const int n = state_dimension();
  state_.mean = Eigen::VectorXd::Zero(n);
  state_.covariance = Eigen::MatrixXd::Zero(n, n);
  Eigen::Matrix3Xd measured(3, estimate_.visible_markers), reference(3, estimate_.visible_markers);
  const Eigen::Matrix3Xd zero_pose = body::marker_positions(model_, body::zero_pose(model_));
  int k = 0;
  for (std::size_t u = 0; u < used_markers_.size(); ++u) {
    if (!observed_(3 * u)) continue;
    measured.col(k) = points.col(mapping_.point_of_marker[used_markers_[u]]);
    reference.col(k) = zero_pose.col(used_markers_[u]);
    ++k;
  }
  const Eigen::Vector3d centroid = measured.rowwise().mean();
  reference_rotation_.setIdentity();
  Eigen::Vector3d position = centroid;
  if (options_.rigid_initialisation) {
    const geometry::RigidTransform fit = geometry::fit_rigid_transform(reference, measured);
    reference_rotation_ = fit.rotation;
    position = fit.translation;
  }
  state_.mean.head<3>() = position;
  state_.covariance.diagonal().head<3>().setConstant(std::pow(options_.initial_position_sd_mm, 2));
  if (!options_.rigid_initialisation) {
    // The paper: C_r is the sample covariance of the first frame's markers.
    const Eigen::Matrix3Xd centred = measured.colwise() - centroid;
    state_.covariance.topLeftCorner<3, 3>() =
        centred * centred.transpose() / std::max<Eigen::Index>(1, k - 1);
  }
  state_.covariance.diagonal().segment<3>(3).setConstant(std::pow(options_.initial_orientation_sd_rad, 2));
  // Joints: the paper starts every joint at mid-range (Theta = 0); the default
  // starts at the zero pose (standing) but keeps a joint whose zero lies on a
  // limit a little inside it, where sin still has slope, so the filter can move
  // it.
  if (options_.joints_start_near_zero_pose) {
    for (int j = 0; j < joint_count(); ++j) {
      const double lower = model_.joints[j].lower, upper = model_.joints[j].upper;
      if (upper <= lower) continue;
      const double normalised =
          std::clamp((0.0 - 0.5 * (upper + lower)) / (0.5 * (upper - lower)), -0.8, 0.8);
      state_.mean(kRootDofs + j) = std::asin(normalised);
    }
  }
  state_.covariance.diagonal().tail(joint_count()).setConstant(std::pow(options_.initial_joint_sd, 2));
  if (with_rates()) {
    motion_.mean = Eigen::VectorXd::Zero(2 * n);  // at rest
    motion_.covariance = Eigen::MatrixXd::Zero(2 * n, 2 * n);
    motion_.covariance.topLeftCorner(n, n) = state_.covariance;
    motion_.covariance.diagonal().segment<3>(n).setConstant(std::pow(options_.initial_position_rate_sd, 2));
    motion_.covariance.diagonal().segment<3>(n + 3).setConstant(
        std::pow(options_.initial_orientation_rate_sd, 2));
    motion_.covariance.diagonal()
        .tail(joint_count())
        .setConstant(std::pow(options_.initial_joint_rate_sd, 2));
  }
  initialised_ = true;
  frames_since_start_ = 0;
}

S2KF_INLINE void Tracker::predict_constant_velocity() {
  const Eigen::Index n = state_dimension();
  const double dt = 1.0 / rate_hz_;
  Eigen::VectorXd& m = motion_.mean;
  Eigen::MatrixXd& c = motion_.covariance;
  m.head(n) += dt * m.tail(n);
  // C_pp += dt (C_pv + C_vp) + dt^2 C_vv, C_pv += dt C_vv (and C_vp as its
  // transpose), then + Q.
  c.topLeftCorner(n, n) +=
      dt * (c.topRightCorner(n, n) + c.bottomLeftCorner(n, n)) + (dt * dt) * c.bottomRightCorner(n, n);
  c.topRightCorner(n, n) += dt * c.bottomRightCorner(n, n);
  c.bottomLeftCorner(n, n) = c.topRightCorner(n, n).transpose();
  c += process_noise_;
  state_.mean = m.head(n);
  state_.covariance = c.topLeftCorner(n, n);
}

S2KF_INLINE void Tracker::condition_rates() {
  if (marginal_update_.apply(motion_, state_)) return;
  motion_.mean.head(state_dimension()) = state_.mean;
  motion_.covariance.topLeftCorner(state_dimension(), state_dimension()) = state_.covariance;
}

S2KF_INLINE void Tracker::recentre() {
  const Eigen::Matrix3d turn = body::rotation_exp(state_.mean.segment<3>(3));
  measurement_model_.recenter(state_.mean);
  reference_rotation_ = measurement_model_.reference_orientation();
  if (!with_rates()) {
    fold_joint_parameters(state_.mean, state_.covariance);
    keep_joint_parameters_learnable(state_.mean, state_.covariance, options_.joint_parameter_margin,
                                    options_.joint_parameter_max_sd);
    return;
  }
  motion_.mean.segment<3>(3).setZero();
  turn_orientation_rate(motion_.mean, motion_.covariance, turn);
  fold_joint_parameters(motion_.mean, motion_.covariance, true);
  keep_joint_parameters_learnable(motion_.mean, motion_.covariance, options_.joint_parameter_margin,
                                  options_.joint_parameter_max_sd, true);
  const Eigen::Index n = state_dimension();
  state_.mean = motion_.mean.head(n);
  state_.covariance = motion_.covariance.topLeftCorner(n, n);
}

S2KF_INLINE void Tracker::finish(const Eigen::Matrix3Xd& points,
                                 const Eigen::Array<bool, Eigen::Dynamic, 1>& visible,
                                 std::chrono::steady_clock::time_point start) {
  estimate_.marker_distance.setConstant(std::numeric_limits<double>::quiet_NaN());
  estimate_.mean_marker_distance = std::numeric_limits<double>::quiet_NaN();
  if (estimate_.tracked) {
    estimate_.root_rotation = reference_rotation_;
    measurement_model_.set_reference_orientation(reference_rotation_);
    write_pose(estimate_.pose);
    estimate_.covariance = state_.covariance;  // same size every frame: no allocation
    // Every model marker at the mean, through the batched model (allocation-free after its first
    // call; the next frame's samples are drawn about the same mean and reuse it); it equals
    // marker_positions(model_, pose) to rounding.
    const Eigen::Index markers = model_.marker_count();
    if (estimate_.predicted_markers.cols() != markers) estimate_.predicted_markers.resize(3, markers);
    estimate_.predicted_markers.reshaped() = measurement_model_.markers_at(state_.mean);
    double sum = 0;
    int count = 0;
    for (int m = 0; m < model_.marker_count(); ++m) {
      const int point = mapping_.point_of_marker[m];
      if (point < 0 || point >= points.cols() || !visible(point) || !points.col(point).allFinite()) continue;
      const double d = (points.col(point) - estimate_.predicted_markers.col(m)).norm();
      estimate_.marker_distance(m) = d;
      sum += d;
      ++count;
    }
    if (count > 0) estimate_.mean_marker_distance = sum / count;
  }
  estimate_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

S2KF_INLINE void Tracker::write_pose(body::Pose& pose) const {
  pose.root_position = state_.mean.head<3>();
  pose.root_rpy = body::rpy_from_rotation(measurement_model_.root_rotation(state_.mean.segment<3>(3)));
  const body::BoundedJoints& joints = measurement_model_.bounded_joints();
  if (pose.joints.size() != joint_count()) pose.joints.resize(joint_count());
  for (int j = 0; j < joint_count(); ++j) pose.joints(j) = joints.angle(j, state_.mean(kRootDofs + j));
}
}  // namespace s2kf::track
