/// @file
/// The tracker's measurement model: a block of 46-dimensional states [root position (mm), root
/// orientation (3), bounded joint parameters Theta (40)] -> the stacked positions of the markers,
/// evaluated for all samples at once with batched forward kinematics; and the marker noise matrix.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/bounded_joints.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/body/vector_sincos.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/error.hpp>
#include <s2kf/core/instruction_set.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::body {

/// What the three orientation numbers of the state mean.
enum class OrientationParameterization {
  /// (roll, pitch, yaw), R = Rz(yaw) Ry(pitch) Rx(roll): the paper's choice; singular at pitch +-90 deg.
  roll_pitch_yaw,
  /// A rotation vector delta about a reference orientation the caller sets: R = R_ref Exp(delta).
  /// Re-centring after each update keeps delta small, so no attitude is singular (handstands).
  local_rotation_error,
};

/// Measurement model h(x) = stacked marker positions [x0, y0, z0, x1, ...] (mm) of the selected
/// markers, for the filter's contract `h(states (n x L), predictions (m x L, sized by the filter))`.
/// Not thread-safe (it owns its scratch memory); after the first call it does not allocate.
class MarkerMeasurementModel {
 public:
  explicit MarkerMeasurementModel(
      BodyModel model, OrientationParameterization orientation = OrientationParameterization::roll_pitch_yaw)
      : model_(std::move(model)), joints_(model_), orientation_(orientation) {
    model_.validate();
    selected_.resize(model_.marker_count());
    for (int m = 0; m < model_.marker_count(); ++m) selected_[m] = m;
  }

  const BodyModel& model() const { return model_; }
  const BoundedJoints& bounded_joints() const { return joints_; }
  OrientationParameterization orientation() const { return orientation_; }

  Eigen::Index state_dimension() const { return 6 + model_.joint_count(); }
  Eigen::Index measurement_dimension() const { return 3 * static_cast<Eigen::Index>(selected_.size()); }

  /// Predict only these model markers, in this order (e.g. in the order of a recording's labels).
  void select_markers(std::vector<int> marker_indices) {
    for (int m : marker_indices)
      if (m < 0 || m >= model_.marker_count())
        throw std::invalid_argument("MarkerMeasurementModel: marker index " + std::to_string(m) +
                                    " is not a marker of the model");
    selected_ = std::move(marker_indices);
  }
  const std::vector<int>& selected_markers() const { return selected_; }

  /// R_ref of the local_rotation_error parameterisation (ignored for roll_pitch_yaw).
  void set_reference_orientation(const Eigen::Matrix3d& reference) { reference_ = reference; }
  const Eigen::Matrix3d& reference_orientation() const { return reference_; }

  /// The root rotation that the orientation part of a state stands for.
  Eigen::Matrix3d root_rotation(const Eigen::Vector3d& orientation_part) const {
    return orientation_ == OrientationParameterization::roll_pitch_yaw
               ? rotation_from_rpy(orientation_part)
               : reference_ * rotation_exp(orientation_part);
  }

  /// local_rotation_error: moves the orientation of `state` into the reference (R_ref <- R_ref
  /// Exp(delta)) and sets delta to 0; the represented pose is unchanged. No-op for roll_pitch_yaw.
  void recenter(Eigen::Ref<Eigen::VectorXd> state) {
    if (orientation_ != OrientationParameterization::local_rotation_error) return;
    check_state_size(state.size(), "recenter");
    reference_ = reference_ * rotation_exp(state.segment<3>(3));
    state.segment<3>(3).setZero();
  }

  /// The pose a state stands for (joint angles through the bounded map).
  Pose pose(const Eigen::Ref<const Eigen::VectorXd>& state) const;

  /// A state that stands for `pose` (Theta on the principal branch; delta = Log(R_ref^T R)).
  Eigen::VectorXd state(const Pose& pose) const;

  /// predictions.col(i) = h(states.col(i)); predictions must be measurement_dimension() x L. Takes
  /// Refs so column blocks work too; the filter's (const MatrixXd&, MatrixXd&) binds without copies.
  void operator()(const Eigen::Ref<const Eigen::MatrixXd>& states, Eigen::Ref<Eigen::MatrixXd> predictions);

  /// Forward kinematics of the samples in single precision (float staging, sine and cosine, joint
  /// chain and markers; the predictions are still returned as doubles): about twice as fast with
  /// wide SIMD, with marker positions rounded to about 1e-4 mm at the scale of a body. Off by
  /// default; the tracker turns it on for its sample pipeline (TrackerOptions).
  void set_single_precision(bool single) { single_precision_ = single; }
  bool single_precision() const { return single_precision_; }

  /// The predictions of a symmetric sample set, whose columns are the mean `origin_count` times,
  /// then mean + H and mean - H (H = half_deviations, one column per pair); `states` holds those
  /// columns. With set_single_precision_deviations on (and set_single_precision off), the mean
  /// pose is evaluated once in double and each sample as its deviation from it in float
  /// (forward_kinematics_deviation_block): float rounds a deviation relative to its own size, not
  /// to the lab coordinates', and what the sample shares with the mean is not recomputed. Else
  /// the same as operator()(states, predictions). The filter calls it when the model has it.
  void evaluate_symmetric(const Eigen::Ref<const Eigen::MatrixXd>& states,
                          const Eigen::Ref<const Eigen::VectorXd>& mean,
                          const Eigen::Ref<const Eigen::MatrixXd>& half_deviations, Eigen::Index origin_count,
                          Eigen::Ref<Eigen::MatrixXd> predictions);
  /// The same deviations for the filter's single-precision moments, without the round trip through
  /// double predictions: `deviations` (measurement_dimension() x (origin_count + 2 H.cols()))
  /// receives each sample's predictions minus the mean pose's in float, `mean_prediction` the mean
  /// pose's in double; H in float. False (nothing written) where set_single_precision_deviations is
  /// off or set_single_precision on: then evaluate_symmetric is the way.
  bool evaluate_symmetric_deviations(const Eigen::Ref<const Eigen::VectorXd>& mean,
                                     const Eigen::Ref<const Eigen::MatrixXf>& half_deviations,
                                     Eigen::Index origin_count, Eigen::Ref<Eigen::MatrixXf> deviations,
                                     Eigen::Ref<Eigen::VectorXd> mean_prediction);
  /// Every model marker (3 M: x0, y0, z0, x1, ...) at one state, in double whatever
  /// set_single_precision says. Kept with the state and the reference orientation: evaluate_symmetric
  /// about the same mean (the next frame of a tracker) does not evaluate it again.
  const Eigen::VectorXd& markers_at(const Eigen::Ref<const Eigen::VectorXd>& state) {
    check_state_size(state.size(), "markers_at");
    evaluate_mean_pose(state);
    return mean_markers_;
  }

  void set_single_precision_deviations(bool single) { single_precision_deviations_ = single; }
  bool single_precision_deviations() const { return single_precision_deviations_; }

 private:
  static constexpr Eigen::Index S = ForwardKinematicsWorkspace::kStride;  // spacing of the arrays

  // predictions.col(i) = the selected markers (with `all_markers` every model marker) at states.col(i).
  template <typename Scalar>
  void evaluate(const Eigen::Ref<const Eigen::MatrixXd>& states, Eigen::Ref<Eigen::MatrixXd> predictions,
                BasicForwardKinematicsWorkspace<Scalar>& ws, std::vector<Scalar>& orientation,
                bool all_markers = false) {
    const Eigen::Index count = states.cols();
    const int joint_count = model_.joint_count();
    ws.prepare(model_, all_markers ? model_.marker_count() : static_cast<Eigen::Index>(selected_.size()));
    const std::vector<int>& markers = all_markers ? ws.all_markers : selected_;
    if (orientation.size() != static_cast<std::size_t>(9 * S)) orientation.assign(9 * S, Scalar(0));
    const Eigen::Index B = ForwardKinematicsWorkspace::block_size(count);
    eigen_assert(states.innerStride() == 1 && predictions.innerStride() == 1);
    const InstructionSet set = active_instruction_set();
    for (Eigen::Index start = 0; start < count; start += B) {
      const Eigen::Index n = std::min(B, count - start);
      // The whole block in one function compiled for the active instruction set: every stage below
      // is a plain loop over the poses, inlined into it.
      run_with_instruction_set(set, [&](auto tag) S2KF_ALWAYS_INLINE_LAMBDA {
        const double* in = states.data() + start * states.outerStride();
        for (Eigen::Index i = 0; i < n; ++i, in += states.outerStride()) {
          for (int r = 0; r < 3; ++r) ws.root_position[r * S + i] = static_cast<Scalar>(in[r]);
          for (int k = 0; k < 3; ++k) orientation[k * S + i] = static_cast<Scalar>(in[3 + k]);
          for (int j = 0; j < joint_count; ++j) ws.angles[j * S + i] = static_cast<Scalar>(in[6 + j]);
        }
        if (orientation_ == OrientationParameterization::roll_pitch_yaw)
          stage_rpy_rotations(n, ws, orientation.data());
        else
          stage_local_rotations(n, ws, orientation.data());
        stage_joint_angles(n, ws);
        forward_kinematics_block(model_, markers, ws, n);
        copy_markers_out<decltype(tag)::value>(ws, n, predictions.data() + start * predictions.outerStride(),
                                               predictions.rows(), predictions.outerStride());
      });
    }
  }

  // evaluate_symmetric with float deviations: the mean pose in double (ws_mean_), then every block
  // of samples as deviations from it (ws_deviation_), written to `out` (rows x count, column-major)
  // as predictions in double (the mean's added) or as the deviations themselves in float.
  template <typename HalfScalar, typename OutScalar>
  void evaluate_deviations(
      const Eigen::Ref<const Eigen::VectorXd>& mean,
      const Eigen::Ref<const Eigen::Matrix<HalfScalar, Eigen::Dynamic, Eigen::Dynamic>>& half,
      Eigen::Index origin_count, OutScalar* out, Eigen::Index out_stride, Eigen::Index count) {
    const Eigen::Index h = half.cols(), rows = measurement_dimension();
    const int joint_count = model_.joint_count();
    evaluate_mean_pose(mean);
    mean_prediction_.resize(rows);
    for (std::size_t k = 0; k < selected_.size(); ++k)
      mean_prediction_.segment<3>(3 * static_cast<Eigen::Index>(k)) =
          mean_markers_.segment<3>(3 * selected_[k]);
    ws_deviation_.prepare_deviations(model_, static_cast<Eigen::Index>(selected_.size()));
    ws_.prepare(model_,
                static_cast<Eigen::Index>(selected_.size()));  // the samples' root rotations in double
    if (orientation_buffer_.size() != static_cast<std::size_t>(9 * S)) orientation_buffer_.assign(9 * S, 0.0);
    const Eigen::Index B = ForwardKinematicsWorkspace::block_size(count);
    eigen_assert(half.innerStride() == 1);
    const InstructionSet set = active_instruction_set();
    for (Eigen::Index start = 0; start < count; start += B) {
      const Eigen::Index n = std::min(B, count - start);
      run_with_instruction_set(set, [&](auto tag) S2KF_ALWAYS_INLINE_LAMBDA {
        BasicForwardKinematicsWorkspace<float>& ws = ws_deviation_;
        double* o = orientation_buffer_.data();
        for (Eigen::Index i = 0; i < n; ++i) {
          // Sample start + i: the mean, mean + H(:, k) or mean - H(:, k).
          const Eigen::Index g = start + i;
          const double sign = g < origin_count ? 0.0 : (g < origin_count + h ? 1.0 : -1.0);
          const Eigen::Index k = g < origin_count ? 0 : (g - origin_count) % h;
          const HalfScalar* d = half.data() + k * half.outerStride();
          for (int r = 0; r < 3; ++r) ws.root_position[r * S + i] = static_cast<float>(sign * d[r]);
          for (int a = 0; a < 3; ++a) o[a * S + i] = mean(3 + a) + sign * static_cast<double>(d[3 + a]);
          for (int j = 0; j < joint_count; ++j)
            ws.angles[j * S + i] = static_cast<float>(0.5 * sign * d[6 + j]);
        }
        // The root's rotation in double, as evaluate() forms it, minus the mean pose's: exact to
        // double rounding before it is rounded to float.
        if (orientation_ == OrientationParameterization::roll_pitch_yaw)
          stage_rpy_rotations(n, ws_, o);
        else
          stage_local_rotations(n, ws_, o);
        for (int a = 0; a < 9; ++a) {
          const double mean_entry = ws_mean_.root_rotation[a * S];
          const double* full = ws_.root_rotation.data() + a * S;
          float* deviation = ws.root_rotation.data() + a * S;
          for (Eigen::Index i = 0; i < n; ++i) deviation[i] = static_cast<float>(full[i] - mean_entry);
        }
        // One block holds every pair: the - half's sines mirror the + half's (see below).
        stage_joint_deviations(n, ws, n == count ? origin_count : -1, h);
        forward_kinematics_deviation_block(model_, selected_, ws, mean_rotation_.data(), n);
        if constexpr (std::is_same_v<OutScalar, float>)
          copy_deviations_out<decltype(tag)::value>(ws, n, out + start * out_stride, rows, out_stride);
        else
          copy_markers_out<decltype(tag)::value>(ws, n, out + start * out_stride, rows, out_stride,
                                                 mean_prediction_.data());
      });
    }
  }

  // Every marker at the mean pose in double (ws_mean_, mean_markers_) and prepare_mean_constants;
  // nothing where the last call had the same mean and reference orientation (the tracker's
  // reported markers, then the next frame's samples about the same mean).
  void evaluate_mean_pose(const Eigen::Ref<const Eigen::VectorXd>& mean) {
    if (mean_evaluated_ && mean_state_.size() == mean.size() && mean_state_ == mean &&
        mean_reference_ == reference_)
      return;
    mean_markers_.resize(3 * model_.marker_count());
    evaluate(mean, Eigen::Map<Eigen::MatrixXd>(mean_markers_.data(), mean_markers_.size(), 1), ws_mean_,
             orientation_mean_, true);
    prepare_mean_constants(mean, model_.frame_count(), model_.joint_count());
    mean_state_ = mean;
    mean_reference_ = reference_;
    mean_evaluated_ = true;
  }

  // From the mean pose's evaluation (ws_mean_): its frames' rotations in float and, per joint,
  // sin and cos of its parameter Theta and of its angle theta, and half its range.
  void prepare_mean_constants(const Eigen::Ref<const Eigen::VectorXd>& mean, int frame_count,
                              int joint_count) {
    mean_rotation_.resize(9 * static_cast<std::size_t>(frame_count));
    for (int f = 0; f < frame_count; ++f)
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
          mean_rotation_[static_cast<std::size_t>(9 * f + 3 * c + r)] =
              static_cast<float>(ws_mean_.rotation[static_cast<std::size_t>(
                  (9 * ws_mean_.column_frame[3 * f + c] + 3 * c + r) * S)]);
    joint_constants_.resize(5 * static_cast<std::size_t>(joint_count));
    for (int j = 0; j < joint_count; ++j) {
      float* constants = joint_constants_.data() + 5 * j;
      const double parameter = mean(6 + j);
      constants[0] = static_cast<float>(std::sin(parameter));
      constants[1] = static_cast<float>(std::cos(parameter));
      constants[2] = static_cast<float>(ws_mean_.sin_q[static_cast<std::size_t>(j * S)]);
      constants[3] = static_cast<float>(ws_mean_.cos_q[static_cast<std::size_t>(j * S)]);
      constants[4] =
          static_cast<float>(0.25 * (joints_.upper(j) - joints_.lower(j)));  // a quarter: see below
    }
  }

  // ws.angles holds half of each sample's parameter deviation d; writes the sine and cosine of
  // its angle and their deviations from the mean's, with sin(x + d) - sin x = cos x sin d -
  // sin x (1 - cos d), sin d = 2 sin(d/2) cos(d/2) and 1 - cos d = 2 sin^2(d/2): no difference of
  // two nearly equal numbers, so each stays precise relative to its own size. With origin >= 0
  // the block is the whole set (origin poses, h pairs' + halves, their - halves), and the sine and
  // cosine of -d/2 are those of d/2, one negated.
  S2KF_ALWAYS_INLINE void stage_joint_deviations(Eigen::Index n, BasicForwardKinematicsWorkspace<float>& ws,
                                                 Eigen::Index origin, Eigen::Index h) {
    for (int j = 0; j < model_.joint_count(); ++j) {
      float* q = ws.array(ws.angles, j);
      float* s = ws.array(ws.sin_q, j);
      float* c = ws.array(ws.cos_q, j);
      float* ds = ws.array(ws.delta_sin_q, j);
      float* dc = ws.array(ws.delta_cos_q, j);
      const float* constants = joint_constants_.data() + 5 * j;
      const float sin_parameter = constants[0], cos_parameter = constants[1];
      const float sin_angle = constants[2], cos_angle = constants[3], quarter_range = constants[4];
      if (joints_.upper(j) == joints_.lower(j)) {
        std::fill(ds, ds + n, 0.0f);
        std::fill(dc, dc + n, 0.0f);
        std::fill(s, s + n, sin_angle);
        std::fill(c, c + n, cos_angle);
        continue;
      }
      if (origin >= 0) {
        vector_sincos(q + origin, s + origin, c + origin, h);
        std::fill(s, s + origin, 0.0f);
        std::fill(c, c + origin, 1.0f);
        for (Eigen::Index k = 0; k < h; ++k) {
          s[origin + h + k] = -s[origin + k];
          c[origin + h + k] = c[origin + k];
        }
      } else {
        vector_sincos(q, s, c, n);
      }
      // theta - theta_mean = half range (sin Theta - sin Theta_mean); q receives half of it.
      for (Eigen::Index i = 0; i < n; ++i)
        q[i] = quarter_range * (cos_parameter * (2.0f * s[i] * c[i]) - sin_parameter * (2.0f * s[i] * s[i]));
      vector_sincos(q, s, c, n);
      add_angle_deviations(s, c, ds, dc, sin_angle, cos_angle, n);
    }
  }

  // s, c: sine and cosine of half of each sample's angle deviation; out: the deviations of the
  // angle's sine and cosine (ds, dc) and the sine and cosine themselves (s, c). Parameters, so that
  // the compiler takes their __restrict and vectorises without overlap checks.
  static S2KF_ALWAYS_INLINE void add_angle_deviations(float* __restrict s, float* __restrict c,
                                                      float* __restrict ds, float* __restrict dc,
                                                      float sin_angle, float cos_angle, Eigen::Index n) {
    for (Eigen::Index i = 0; i < n; ++i) {
      const float sine = 2.0f * s[i] * c[i], versine = 2.0f * s[i] * s[i];
      ds[i] = cos_angle * sine - sin_angle * versine;
      dc[i] = -sin_angle * sine - cos_angle * versine;
      s[i] = sin_angle + ds[i];
      c[i] = cos_angle + dc[i];
    }
  }

  void check_state_size(Eigen::Index n, const char* where) const {
    if (n != state_dimension())
      throw DimensionError(std::string("MarkerMeasurementModel::") + where + ": state dimension " +
                           std::to_string(n) + ", expected " + std::to_string(state_dimension()));
  }

  void check_predictions_size(const Eigen::Ref<Eigen::MatrixXd>& predictions, Eigen::Index count) const {
    if (predictions.rows() != measurement_dimension() || predictions.cols() != count)
      throw DimensionError("MarkerMeasurementModel: predictions must be " +
                           std::to_string(measurement_dimension()) + " x " + std::to_string(count) +
                           ", got " + std::to_string(predictions.rows()) + " x " +
                           std::to_string(predictions.cols()));
  }

  // orientation_buffer_ holds roll, pitch, yaw in arrays 0..2; arrays 3..8 receive sines and cosines.
  template <typename Scalar>
  S2KF_ALWAYS_INLINE void stage_rpy_rotations(Eigen::Index n, BasicForwardKinematicsWorkspace<Scalar>& ws,
                                              Scalar* o) {
    for (int k = 0; k < 3; ++k) vector_sincos(o + k * S, o + (3 + k) * S, o + (6 + k) * S, n);
    const Scalar *sr = o + 3 * S, *sp = o + 4 * S, *sy = o + 5 * S;
    const Scalar *cr = o + 6 * S, *cp = o + 7 * S, *cy = o + 8 * S;
    Scalar* R = ws.root_rotation.data();  // entry (r, c) at array 3 c + r
    for (Eigen::Index i = 0; i < n; ++i) {
      R[0 * S + i] = cy[i] * cp[i];
      R[1 * S + i] = sy[i] * cp[i];
      R[2 * S + i] = -sp[i];
      R[3 * S + i] = cy[i] * sp[i] * sr[i] - sy[i] * cr[i];
      R[4 * S + i] = sy[i] * sp[i] * sr[i] + cy[i] * cr[i];
      R[5 * S + i] = cp[i] * sr[i];
      R[6 * S + i] = cy[i] * sp[i] * cr[i] + sy[i] * sr[i];
      R[7 * S + i] = sy[i] * sp[i] * cr[i] - cy[i] * sr[i];
      R[8 * S + i] = cp[i] * cr[i];
    }
  }

  // R = R_ref Exp(delta), Exp(delta) = I + a K + b K^2 with K = [delta]x, a = sin t / t,
  // b = (1 - cos t) / t^2 (series below t = 1e-4, where both are exact to rounding).
  template <typename Scalar>
  S2KF_ALWAYS_INLINE void stage_local_rotations(Eigen::Index n, BasicForwardKinematicsWorkspace<Scalar>& ws,
                                                Scalar* o) {
    const Scalar *dx = o, *dy = o + S, *dz = o + 2 * S;
    Scalar *t = o + 3 * S, *st = o + 4 * S, *ct = o + 5 * S;
    for (Eigen::Index i = 0; i < n; ++i) t[i] = std::sqrt(dx[i] * dx[i] + dy[i] * dy[i] + dz[i] * dz[i]);
    vector_sincos(t, st, ct, n);
    Scalar* E = ws.root_rotation.data();  // Exp(delta) first, entry (r, c) at array 3 c + r
    const Scalar one(1), series_below(1e-4), half(0.5), six(6), twenty_four(24);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Scalar t2 = t[i] * t[i];
      const bool small = t[i] < series_below;
      const Scalar safe_t = small ? one : t[i];
      const Scalar a = small ? one - t2 / six : st[i] / safe_t;
      const Scalar b = small ? half - t2 / twenty_four : (one - ct[i]) / (safe_t * safe_t);
      const Scalar x = dx[i], y = dy[i], z = dz[i];
      E[0 * S + i] = one - b * (y * y + z * z);
      E[1 * S + i] = a * z + b * x * y;
      E[2 * S + i] = -a * y + b * x * z;
      E[3 * S + i] = -a * z + b * x * y;
      E[4 * S + i] = one - b * (x * x + z * z);
      E[5 * S + i] = a * x + b * y * z;
      E[6 * S + i] = a * y + b * x * z;
      E[7 * S + i] = -a * x + b * y * z;
      E[8 * S + i] = one - b * (x * x + y * y);
    }
    // R(r, c) = sum_k R_ref(r, k) E(k, c); the nine E arrays are copied aside first.
    std::copy(E, E + 9 * S, o);
    const Scalar* Ec = o;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        Scalar* out = E + (3 * c + r) * S;
        const Scalar *e0 = Ec + (3 * c + 0) * S, *e1 = Ec + (3 * c + 1) * S, *e2 = Ec + (3 * c + 2) * S;
        const auto r0 = static_cast<Scalar>(reference_(r, 0)), r1 = static_cast<Scalar>(reference_(r, 1)),
                   r2 = static_cast<Scalar>(reference_(r, 2));
        for (Eigen::Index i = 0; i < n; ++i) out[i] = r0 * e0[i] + r1 * e1[i] + r2 * e2[i];
      }
  }

  // theta = bounded_angle_from_sine(sin Theta) per sample, then sin and cos of theta.
  template <typename Scalar>
  S2KF_ALWAYS_INLINE void stage_joint_angles(Eigen::Index n, BasicForwardKinematicsWorkspace<Scalar>& ws) {
    for (int j = 0; j < model_.joint_count(); ++j) {
      Scalar* q = ws.array(ws.angles, j);
      Scalar* s = ws.array(ws.sin_q, j);
      Scalar* c = ws.array(ws.cos_q, j);
      const auto lower = static_cast<Scalar>(joints_.lower(j)), upper = static_cast<Scalar>(joints_.upper(j));
      if (joints_.upper(j) == joints_.lower(j)) {
        std::fill(q, q + n, lower);
      } else {
        vector_sincos(q, s, c, n);
        for (Eigen::Index i = 0; i < n; ++i) q[i] = bounded_angle_from_sine(s[i], lower, upper);
      }
      vector_sincos(q, s, c, n);
    }
  }

  BodyModel model_;
  BoundedJoints joints_;
  OrientationParameterization orientation_;
  Eigen::Matrix3d reference_ = Eigen::Matrix3d::Identity();
  std::vector<int> selected_;
  ForwardKinematicsWorkspace ws_;
  std::vector<double> orientation_buffer_;
  bool single_precision_ = false;
  BasicForwardKinematicsWorkspace<float> ws_single_;
  std::vector<float> orientation_single_;
  // evaluate_symmetric's float deviations: the mean pose's evaluation and predictions, its frames'
  // rotations and per-joint constants (prepare_mean_constants), and the samples' workspace.
  bool single_precision_deviations_ = false;
  ForwardKinematicsWorkspace ws_mean_;
  std::vector<double> orientation_mean_;
  // evaluate_mean_pose: every marker at the mean, and the mean and reference it was evaluated at.
  Eigen::VectorXd mean_markers_, mean_state_;
  Eigen::Matrix3d mean_reference_ = Eigen::Matrix3d::Identity();
  bool mean_evaluated_ = false;
  Eigen::VectorXd mean_prediction_;
  std::vector<float> mean_rotation_, joint_constants_;
  BasicForwardKinematicsWorkspace<float> ws_deviation_;
};

/// Diagonal measurement noise R (3 M x 3 M) with the same variance (mm^2) for every coordinate.
Eigen::MatrixXd marker_noise(double variance_mm2, Eigen::Index marker_count);

/// Diagonal measurement noise R (3 M x 3 M) with one variance (mm^2) per marker, for all 3 coordinates.
Eigen::MatrixXd marker_noise(const Eigen::Ref<const Eigen::VectorXd>& variance_mm2_per_marker);

}  // namespace s2kf::body

#if !defined(S2KF_COMPILED)
#include <s2kf/body/marker_measurement_model.hxx>
#endif
