/// @file
/// Forward kinematics of a BodyModel: world frames and marker positions of one pose, of a block of
/// poses at once (structure-of-arrays, allocation-free with a reusable workspace), and the analytic
/// Jacobian of the marker positions.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/body/vector_sincos.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/error.hpp>
#include <s2kf/core/instruction_set.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace s2kf::body {

/// World rotation and origin (mm) of every frame of a model: index 0 is the root, index j + 1 the
/// frame after joint j.
struct FrameTransforms {
  std::vector<Eigen::Matrix3d> rotations;
  std::vector<Eigen::Vector3d> origins;
};

namespace detail {
inline void check_joint_count(const BodyModel& model, Eigen::Index joints, const char* where) {
  if (joints != model.joint_count())
    throw DimensionError(std::string(where) + ": " + std::to_string(joints) +
                         " joint angles for a model with " + std::to_string(model.joint_count()) + " joints");
}
}  // namespace detail

/// Frames of one pose; the root rotation is given as a matrix (any orientation parameterisation).
FrameTransforms joint_frames(const BodyModel& model, const Eigen::Vector3d& root_position,
                             const Eigen::Matrix3d& root_rotation,
                             const Eigen::Ref<const Eigen::VectorXd>& joint_angles);

FrameTransforms joint_frames(const BodyModel& model, const Pose& pose);

/// Marker positions (mm, lab frame), one column per model marker, from already computed frames.
Eigen::Matrix3Xd marker_positions(const BodyModel& model, const FrameTransforms& frames);

Eigen::Matrix3Xd marker_positions(const BodyModel& model, const Eigen::Vector3d& root_position,
                                  const Eigen::Matrix3d& root_rotation,
                                  const Eigen::Ref<const Eigen::VectorXd>& joint_angles);

/// Marker positions (3 x marker_count, mm, lab frame) of one pose.
Eigen::Matrix3Xd marker_positions(const BodyModel& model, const Pose& pose);

/// Jacobian (3 M x (6 + J)) of the stacked marker positions [x0, y0, z0, x1, ...] with respect to
/// [root position (3), root roll, pitch, yaw (3), joint angles (J)]. A joint moves the markers
/// downstream of it by w x (p - o), w its world axis and o its centre; roll, pitch and yaw rotate
/// about Rz Ry e_x, Rz e_y and e_z through the root.
Eigen::MatrixXd marker_jacobian(const BodyModel& model, const Eigen::Vector3d& root_position,
                                const Eigen::Vector3d& root_rpy,
                                const Eigen::Ref<const Eigen::VectorXd>& joint_angles);

Eigen::MatrixXd marker_jacobian(const BodyModel& model, const Pose& pose);

/// Scratch memory of batched forward kinematics (the Pinocchio "Data" to the model's "Model").
/// Poses are processed in blocks of at most kBlock (block_size() splits a batch evenly); every
/// buffer holds one array of kBlock numbers per quantity (structure of arrays, arrays kStride
/// apart), so the inner loops run over poses with unit stride and vectorise. Long arrays pay: the
/// loop over the joints costs the same for a short block, and 301 poses in one block take 0.6 of
/// the time of five blocks of 64 in float, 0.9 in double (AVX-512). Scalar is double, or float for the
/// tracker's single-precision sample pipeline (twice the poses per SIMD instruction, half the memory
/// traffic). Its size depends only on the model, so after the first call nothing allocates.
template <typename Scalar>
struct BasicForwardKinematicsWorkspace {
  static constexpr Eigen::Index kBlock = 320;
  /// Arrays are kStride numbers apart: a power-of-two spacing would map the arrays of one pose to
  /// the same cache sets, and the transposes in and out of the block would thrash the L1 cache.
  static constexpr Eigen::Index kStride = kBlock + 4;

  // Inputs of one block, filled by the caller of forward_kinematics_block.
  std::vector<Scalar> root_position;  ///< 3 arrays: x, y, z
  std::vector<Scalar> root_rotation;  ///< 9 arrays: entry (r, c) at index 3 c + r
  std::vector<Scalar> angles;         ///< one array per joint (staging for sin_q, cos_q)
  std::vector<Scalar> sin_q, cos_q;   ///< one array per joint
  /// forward_kinematics_deviation_block only: sin q - sin q_mean and cos q - cos q_mean per joint
  /// (sized by prepare_deviations).
  std::vector<Scalar> delta_sin_q, delta_cos_q;
  // Results of one block.
  std::vector<Scalar> rotation;  ///< 9 arrays per frame, entry (r, c) of frame f at 9 f + 3 c + r
  std::vector<Scalar> origin;    ///< 3 arrays per frame (only frames with their own origin are written)
  std::vector<Scalar> markers;   ///< 3 arrays per requested marker: x, y, z
  /// Frames reached by a zero translation share their parent's origin instead of copying it.
  std::vector<int> origin_frame;
  /// Per frame and column c, the frame whose rotation arrays hold column c: a joint turns two
  /// columns of its parent's rotation, and shares the third (its axis) instead of copying it.
  std::vector<int> column_frame;
  /// 0, 1, ..., M - 1: the marker list of a call that wants every marker.
  std::vector<int> all_markers;

  /// Sizes the buffers for `model` and `marker_count` requested markers (no-op when they fit).
  void prepare(const BodyModel& model, Eigen::Index marker_count) {
    const auto size = [](std::vector<Scalar>& buffer, Eigen::Index arrays) {
      const auto wanted = static_cast<std::size_t>(arrays * kStride);
      if (buffer.size() != wanted) buffer.assign(wanted, Scalar(0));
    };
    size(root_position, 3);
    size(root_rotation, 9);
    size(angles, model.joint_count());
    size(sin_q, model.joint_count());
    size(cos_q, model.joint_count());
    size(rotation, 9 * model.frame_count());
    size(origin, 3 * model.frame_count());
    size(markers, 3 * marker_count);
    origin_frame.resize(model.frame_count());
    origin_frame[0] = 0;
    column_frame.assign(3 * static_cast<std::size_t>(model.frame_count()), 0);
    for (int j = 0; j < model.joint_count(); ++j) {
      const Joint& joint = model.joints[j];
      origin_frame[j + 1] = joint.translation.isZero(0) ? origin_frame[joint.parent_frame] : j + 1;
      for (int c = 0; c < 3; ++c)
        column_frame[3 * (j + 1) + c] =
            c == static_cast<int>(joint.axis) ? column_frame[3 * joint.parent_frame + c] : j + 1;
    }
    all_markers.resize(model.marker_count());
    for (int m = 0; m < model.marker_count(); ++m) all_markers[m] = m;
  }

  /// prepare() and the buffers of forward_kinematics_deviation_block.
  void prepare_deviations(const BodyModel& model, Eigen::Index marker_count) {
    prepare(model, marker_count);
    const auto wanted = static_cast<std::size_t>(model.joint_count() * kStride);
    if (delta_sin_q.size() != wanted) delta_sin_q.assign(wanted, Scalar(0));
    if (delta_cos_q.size() != wanted) delta_cos_q.assign(wanted, Scalar(0));
  }

  Scalar* array(std::vector<Scalar>& buffer, Eigen::Index index) { return buffer.data() + index * kStride; }

  /// Poses per block for a batch of `count`: as few blocks as kBlock allows, of equal size.
  static Eigen::Index block_size(Eigen::Index count) {
    const Eigen::Index blocks = std::max<Eigen::Index>(1, (count + kBlock - 1) / kBlock);
    return (count + blocks - 1) / blocks;
  }
};

using ForwardKinematicsWorkspace = BasicForwardKinematicsWorkspace<double>;

namespace detail {
/// One row of a joint's turn for deviations from the mean pose (forward_kinematics_deviation_block).
/// A function of its own so that the compiler takes the arrays' __restrict (of parameters): the
/// eight arrays need more run-time overlap checks than it makes before it vectorises a loop.
template <typename Scalar>
S2KF_ALWAYS_INLINE void turn_deviation(Scalar* __restrict fu, Scalar* __restrict fv,
                                       const Scalar* __restrict pu, const Scalar* __restrict pv,
                                       const Scalar* __restrict c, const Scalar* __restrict s,
                                       const Scalar* __restrict dc, const Scalar* __restrict ds, Scalar mu,
                                       Scalar mv, Eigen::Index n) {
  for (Eigen::Index i = 0; i < n; ++i) {
    fu[i] = (dc[i] * mu + ds[i] * mv) + (c[i] * pu[i] + s[i] * pv[i]);
    fv[i] = (dc[i] * mv - ds[i] * mu) + (c[i] * pv[i] - s[i] * pu[i]);
  }
}

/// forward_kinematics_block and, with kDeviations, forward_kinematics_deviation_block: the joint
/// chain and the markers. Origins and markers are linear in the frames' rotations and origins, so
/// the deviations pass through the same code; only a joint's rotation differs.
template <bool kDeviations, typename Scalar>
S2KF_ALWAYS_INLINE void forward_kinematics_chain(const BodyModel& model,
                                                 const std::vector<int>& marker_indices,
                                                 BasicForwardKinematicsWorkspace<Scalar>& ws, Eigen::Index n,
                                                 const Scalar* mean_rotation) {
  auto rotation = [&](int frame, int r, int c) {
    return ws.array(ws.rotation, 9 * ws.column_frame[3 * frame + c] + 3 * c + r);
  };
  auto origin = [&](int frame, int r) { return ws.array(ws.origin, 3 * ws.origin_frame[frame] + r); };
  // out = base + R(frame) t (row r), skipping the zero components of t (most joints translate, and
  // most markers sit, along one or two axes); one pass, no copy of `base` first.
  const auto offset = [&](Scalar* __restrict out, const Scalar* __restrict base, int frame, int r,
                          const Eigen::Vector3d& t) S2KF_ALWAYS_INLINE_LAMBDA {
    // The nonzero components of t in order (ta, a), (tb, b), (td, d); the rest are never used.
    int terms = 0;
    Scalar ta = 0, tb = 0, td = 0;
    const Scalar* __restrict a = base, * __restrict b = base, * __restrict d = base;
    for (int c = 0; c < 3; ++c) {
      if (t(c) == 0) continue;
      const auto value = static_cast<Scalar>(t(c));
      const Scalar* column = rotation(frame, r, c);
      if (terms == 0) {
        ta = value;
        a = column;
      } else if (terms == 1) {
        tb = value;
        b = column;
      } else {
        td = value;
        d = column;
      }
      ++terms;
    }
    if (terms == 0)
      for (Eigen::Index i = 0; i < n; ++i) out[i] = base[i];
    else if (terms == 1)
      for (Eigen::Index i = 0; i < n; ++i) out[i] = base[i] + ta * a[i];
    else if (terms == 2)
      for (Eigen::Index i = 0; i < n; ++i) out[i] = (base[i] + ta * a[i]) + tb * b[i];
    else
      for (Eigen::Index i = 0; i < n; ++i) out[i] = ((base[i] + ta * a[i]) + tb * b[i]) + td * d[i];
  };

  for (int k = 0; k < 9; ++k) std::copy_n(ws.array(ws.root_rotation, k), n, ws.array(ws.rotation, k));
  for (int r = 0; r < 3; ++r) std::copy_n(ws.array(ws.root_position, r), n, origin(0, r));

  for (int j = 0; j < model.joint_count(); ++j) {
    const Joint& joint = model.joints[j];
    const int p = joint.parent_frame, f = j + 1;
    if (ws.origin_frame[f] == f)  // o_f = o_p + R_p t
      for (int r = 0; r < 3; ++r) offset(origin(f, r), origin(p, r), p, r, joint.translation);
    // R_f = R_p * R_axis(q): the axis column is the parent's (shared: column_frame), the other
    // two turn by q in their plane.
    const int a = static_cast<int>(joint.axis);
    const int u = (a + 1) % 3, v = (a + 2) % 3;  // (y, z) for x, (z, x) for y, (x, y) for z
    const Scalar* __restrict s = ws.array(ws.sin_q, j);
    const Scalar* __restrict c = ws.array(ws.cos_q, j);
    for (int r = 0; r < 3; ++r) {
      const Scalar* __restrict pu = rotation(p, r, u), * __restrict pv = rotation(p, r, v);
      Scalar* __restrict fu = rotation(f, r, u), * __restrict fv = rotation(f, r, v);
      if constexpr (kDeviations) {
        // f - f_mean = (c - c_mean) pu_mean + (s - s_mean) pv_mean + c (pu - pu_mean) + s (pv - pv_mean):
        // every term as small as the sample's deviation, so float keeps its relative precision.
        turn_deviation(fu, fv, pu, pv, c, s, ws.array(ws.delta_cos_q, j), ws.array(ws.delta_sin_q, j),
                       mean_rotation[9 * p + 3 * u + r], mean_rotation[9 * p + 3 * v + r], n);
      } else {
        for (Eigen::Index i = 0; i < n; ++i) {
          fu[i] = c[i] * pu[i] + s[i] * pv[i];
          fv[i] = c[i] * pv[i] - s[i] * pu[i];
        }
      }
    }
  }

  for (std::size_t k = 0; k < marker_indices.size(); ++k) {
    const Marker& marker = model.markers[marker_indices[k]];
    for (int r = 0; r < 3; ++r)
      offset(ws.array(ws.markers, 3 * static_cast<Eigen::Index>(k) + r), origin(marker.frame, r),
             marker.frame, r, marker.offset);
  }
}
}  // namespace detail

/// Runs forward kinematics on the first n (<= kBlock) poses staged in `ws` (root_position,
/// root_rotation, sin_q, cos_q) and writes ws.markers for the markers listed in `marker_indices`
/// (in that order). `ws.prepare(model, marker_indices.size())` must have been called. Plain loops
/// over the poses, always inlined, so that a caller compiled for another instruction set
/// (core/instruction_set.hpp) vectorises them with its own registers.
template <typename Scalar>
S2KF_ALWAYS_INLINE void forward_kinematics_block(const BodyModel& model,
                                                 const std::vector<int>& marker_indices,
                                                 BasicForwardKinematicsWorkspace<Scalar>& ws,
                                                 Eigen::Index n) {
  detail::forward_kinematics_chain<false>(model, marker_indices, ws, n, static_cast<const Scalar*>(nullptr));
}

/// The same for deviations from a mean pose: ws.root_position and ws.root_rotation hold each pose's
/// root position and rotation minus the mean pose's, ws.sin_q and ws.cos_q each joint's sine and
/// cosine, ws.delta_sin_q and ws.delta_cos_q those minus the mean pose's, and `mean_rotation` the
/// mean pose's frame rotations (entry (r, c) of frame f at 9 f + 3 c + r); ws.markers receives
/// each marker minus the mean pose's. `ws.prepare_deviations(model, marker_indices.size())` must
/// have been called. What a sample shares with the mean pose is never recomputed, and the
/// deviations keep their relative precision in float.
template <typename Scalar>
S2KF_ALWAYS_INLINE void forward_kinematics_deviation_block(const BodyModel& model,
                                                           const std::vector<int>& marker_indices,
                                                           BasicForwardKinematicsWorkspace<Scalar>& ws,
                                                           const Scalar* mean_rotation, Eigen::Index n) {
  detail::forward_kinematics_chain<true>(model, marker_indices, ws, n, mean_rotation);
}

namespace detail {
/// Four doubles in one vector (GCC/Clang vector extension): compiled to the caller's instruction
/// set, one AVX register or two SSE2 ones.
typedef double Double4 __attribute__((vector_size(4 * sizeof(double))));
/// GCC's shuffle mask for Double4 (Clang's __builtin_shufflevector takes the indices as they are).
typedef long long Long4 __attribute__((vector_size(4 * sizeof(long long))));

#if defined(__clang__)
#define S2KF_SHUFFLE4(a, b, i0, i1, i2, i3) __builtin_shufflevector(a, b, i0, i1, i2, i3)
#else
#define S2KF_SHUFFLE4(a, b, i0, i1, i2, i3) __builtin_shuffle(a, b, (Long4{i0, i1, i2, i3}))
#endif

/// to[k * stride + r] = from[r * S + k] + offset[r] for a 4 x 4 tile: four rows of four poses in,
/// four pose columns of four rows out, so that every load and store moves four numbers.
template <typename Scalar, Eigen::Index S>
S2KF_ALWAYS_INLINE void transpose_four(const Scalar* from, double* to, Eigen::Index stride,
                                       const Double4& offset) {
  typedef Scalar Scalar4 __attribute__((vector_size(4 * sizeof(Scalar)), aligned(sizeof(Scalar)), may_alias));
  typedef double Unaligned4
      __attribute__((vector_size(4 * sizeof(double)), aligned(sizeof(double)), may_alias));
  const Double4 r0 = __builtin_convertvector(*reinterpret_cast<const Scalar4*>(from), Double4);
  const Double4 r1 = __builtin_convertvector(*reinterpret_cast<const Scalar4*>(from + S), Double4);
  const Double4 r2 = __builtin_convertvector(*reinterpret_cast<const Scalar4*>(from + 2 * S), Double4);
  const Double4 r3 = __builtin_convertvector(*reinterpret_cast<const Scalar4*>(from + 3 * S), Double4);
  const Double4 t0 = S2KF_SHUFFLE4(r0, r1, 0, 4, 2, 6), t1 = S2KF_SHUFFLE4(r0, r1, 1, 5, 3, 7);
  const Double4 t2 = S2KF_SHUFFLE4(r2, r3, 0, 4, 2, 6), t3 = S2KF_SHUFFLE4(r2, r3, 1, 5, 3, 7);
  *reinterpret_cast<Unaligned4*>(to) = S2KF_SHUFFLE4(t0, t2, 0, 1, 4, 5) + offset;
  *reinterpret_cast<Unaligned4*>(to + stride) = S2KF_SHUFFLE4(t1, t3, 0, 1, 4, 5) + offset;
  *reinterpret_cast<Unaligned4*>(to + 2 * stride) = S2KF_SHUFFLE4(t0, t2, 2, 3, 6, 7) + offset;
  *reinterpret_cast<Unaligned4*>(to + 3 * stride) = S2KF_SHUFFLE4(t1, t3, 2, 3, 6, 7) + offset;
}
#undef S2KF_SHUFFLE4

/// Four floats in one vector, and the mask type of their shuffles.
typedef float Float4 __attribute__((vector_size(4 * sizeof(float))));
typedef int Int4 __attribute__((vector_size(4 * sizeof(int))));
#if defined(__clang__)
#define S2KF_SHUFFLE4F(a, b, i0, i1, i2, i3) __builtin_shufflevector(a, b, i0, i1, i2, i3)
#else
#define S2KF_SHUFFLE4F(a, b, i0, i1, i2, i3) __builtin_shuffle(a, b, (Int4{i0, i1, i2, i3}))
#endif

/// to[k * stride + r] = from[r * S + k] for a 4 x 4 tile of floats (transpose_four without the
/// conversion to double).
template <Eigen::Index S>
S2KF_ALWAYS_INLINE void transpose_four_floats(const float* from, float* to, Eigen::Index stride) {
  typedef float Unaligned4 __attribute__((vector_size(4 * sizeof(float)), aligned(sizeof(float)), may_alias));
  const Float4 r0 = *reinterpret_cast<const Unaligned4*>(from);
  const Float4 r1 = *reinterpret_cast<const Unaligned4*>(from + S);
  const Float4 r2 = *reinterpret_cast<const Unaligned4*>(from + 2 * S);
  const Float4 r3 = *reinterpret_cast<const Unaligned4*>(from + 3 * S);
  const Float4 t0 = S2KF_SHUFFLE4F(r0, r1, 0, 4, 1, 5), t1 = S2KF_SHUFFLE4F(r0, r1, 2, 6, 3, 7);
  const Float4 t2 = S2KF_SHUFFLE4F(r2, r3, 0, 4, 1, 5), t3 = S2KF_SHUFFLE4F(r2, r3, 2, 6, 3, 7);
  *reinterpret_cast<Unaligned4*>(to) = S2KF_SHUFFLE4F(t0, t2, 0, 1, 4, 5);
  *reinterpret_cast<Unaligned4*>(to + stride) = S2KF_SHUFFLE4F(t0, t2, 2, 3, 6, 7);
  *reinterpret_cast<Unaligned4*>(to + 2 * stride) = S2KF_SHUFFLE4F(t1, t3, 0, 1, 4, 5);
  *reinterpret_cast<Unaligned4*>(to + 3 * stride) = S2KF_SHUFFLE4F(t1, t3, 2, 3, 6, 7);
}
#undef S2KF_SHUFFLE4F
}  // namespace detail

/// markers.col(i) = the i-th pose's ws.markers (rows x0, y0, z0, x1, ...), plus `offset` (one number
/// per row, or none), for the first n poses of a block, by code for instruction set `Set`. A
/// transpose, eight rows at a time, so the source arrays and the destination columns in use stay
/// in the L1 cache (row by row, or column by column, they do not); with AVX2 and AVX-512 in 4 x 4
/// tiles (SSE2 has no 4-wide registers).
template <InstructionSet Set = compiled_instruction_set(), typename Scalar>
S2KF_ALWAYS_INLINE void copy_markers_out(const BasicForwardKinematicsWorkspace<Scalar>& ws, Eigen::Index n,
                                         double* markers, Eigen::Index rows, Eigen::Index stride,
                                         const double* offset = nullptr) {
  constexpr Eigen::Index S = BasicForwardKinematicsWorkspace<Scalar>::kStride, kRows = 8;
  const Scalar* from = ws.markers.data();
  const auto add = [offset](Eigen::Index row)
                       S2KF_ALWAYS_INLINE_LAMBDA { return offset != nullptr ? offset[row] : 0.0; };
  Eigen::Index n4 = 0;  // poses done in tiles
  if constexpr (Set >= InstructionSet::avx2) n4 = n - n % 4;
  for (Eigen::Index top = 0; top < rows; top += kRows) {
    const Eigen::Index r = std::min(kRows, rows - top);
    if constexpr (Set >= InstructionSet::avx2) {
      const Eigen::Index r4 = r - r % 4;
      for (Eigen::Index i = 0; i < n4; i += 4) {
        double* to = markers + i * stride + top;
        for (Eigen::Index k = 0; k < r4; k += 4) {
          const detail::Double4 rows_offset{add(top + k), add(top + k + 1), add(top + k + 2),
                                            add(top + k + 3)};
          detail::transpose_four<Scalar, S>(from + (top + k) * S + i, to + k, stride, rows_offset);
        }
        for (Eigen::Index k = r4; k < r; ++k)
          for (Eigen::Index j = 0; j < 4; ++j)
            to[j * stride + k] = from[(top + k) * S + i + j] + add(top + k);
      }
    }
    for (Eigen::Index i = n4; i < n; ++i) {
      double* to = markers + i * stride + top;
      for (Eigen::Index k = 0; k < r; ++k) to[k] = from[(top + k) * S + i] + add(top + k);
    }
  }
}

/// The same in float without an offset, for the deviations from a mean pose
/// (forward_kinematics_deviation_block): markers.col(i) = the i-th pose's ws.markers.
template <InstructionSet Set = compiled_instruction_set()>
S2KF_ALWAYS_INLINE void copy_deviations_out(const BasicForwardKinematicsWorkspace<float>& ws, Eigen::Index n,
                                            float* markers, Eigen::Index rows, Eigen::Index stride) {
  constexpr Eigen::Index S = BasicForwardKinematicsWorkspace<float>::kStride, kRows = 8;
  const float* from = ws.markers.data();
  const Eigen::Index n4 = n - n % 4;
  for (Eigen::Index top = 0; top < rows; top += kRows) {
    const Eigen::Index r = std::min(kRows, rows - top), r4 = r - r % 4;
    for (Eigen::Index i = 0; i < n4; i += 4) {
      float* to = markers + i * stride + top;
      for (Eigen::Index k = 0; k < r4; k += 4)
        detail::transpose_four_floats<S>(from + (top + k) * S + i, to + k, stride);
      for (Eigen::Index k = r4; k < r; ++k)
        for (Eigen::Index j = 0; j < 4; ++j) to[j * stride + k] = from[(top + k) * S + i + j];
    }
    for (Eigen::Index i = n4; i < n; ++i) {
      float* to = markers + i * stride + top;
      for (Eigen::Index k = 0; k < r; ++k) to[k] = from[(top + k) * S + i];
    }
  }
}

template <typename Scalar>
void copy_markers_out(const BasicForwardKinematicsWorkspace<Scalar>& ws, Eigen::Index n,
                      Eigen::Ref<Eigen::MatrixXd> markers) {
  copy_markers_out(ws, n, markers.data(), markers.rows(), markers.outerStride());
}

/// Batched forward kinematics of L poses: root_positions (3 x L, mm), root_rotations (9 x L, the
/// rotation matrix entries row-major: row 3 r + c holds R(r, c)), joint_angles (J x L, rad) ->
/// markers (3 M x L, rows x0, y0, z0, x1, ...; sized by the caller). Does not allocate once `ws`
/// has seen this model. Equal to marker_positions() per pose up to rounding.
void marker_positions_batch(const BodyModel& model, const Eigen::Ref<const Eigen::MatrixXd>& root_positions,
                            const Eigen::Ref<const Eigen::MatrixXd>& root_rotations,
                            const Eigen::Ref<const Eigen::MatrixXd>& joint_angles,
                            ForwardKinematicsWorkspace& ws, Eigen::Ref<Eigen::MatrixXd> markers);

}  // namespace s2kf::body

#if !defined(S2KF_COMPILED)
#include <s2kf/body/forward_kinematics.hxx>
#endif
