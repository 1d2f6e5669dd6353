/// @file
/// The motion data of a viewer page: one little-endian float32 record per shown frame (frame
/// number, time, pose, mean marker distance, skeleton joint centres, model and recorded marker
/// positions, optionally the true skeleton), computed with the library's forward kinematics, and
/// decimated to a stride when the recording would exceed the size limit. Layout in docs/viewer.md.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/motion_files.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::cli::viewer {

/// Binary bytes of motion data a page may hold before frames are decimated (base64 makes the page
/// 4/3 of that): 48 MiB is about 5 minutes at 100 Hz with 50 markers.
inline constexpr std::size_t kDefaultDataLimitBytes = 48u << 20;

/// One named run of floats inside each frame record.
struct DataBlock {
  std::string name;
  int offset = 0;  ///< in floats from the record's start
  int count = 0;   ///< floats
};

/// The points the page draws the skeleton with: the root and every frame that has its own joint
/// centre (the 2nd and 3rd DoF of a joint group share the first one's), linked parent to child.
struct Skeleton {
  std::vector<int> frames;                 ///< model frame index of each point
  std::vector<std::string> names;          ///< "root" or the joint group, e.g. "LK"
  std::vector<std::pair<int, int>> bones;  ///< point indices, parent first
};

inline Skeleton skeleton_of(const body::BodyModel& model) {
  Skeleton skeleton;
  std::vector<int> point_of_frame(static_cast<std::size_t>(model.frame_count()), -1);
  skeleton.frames.push_back(0);
  skeleton.names.push_back("root");
  point_of_frame[0] = 0;
  for (int j = 0; j < model.joint_count(); ++j) {
    const body::Joint& joint = model.joints[static_cast<std::size_t>(j)];
    const int parent_point = point_of_frame[static_cast<std::size_t>(joint.parent_frame)];
    if (joint.translation.isZero(0)) {
      point_of_frame[static_cast<std::size_t>(j + 1)] = parent_point;  // same centre as its parent
      continue;
    }
    const int point = static_cast<int>(skeleton.frames.size());
    point_of_frame[static_cast<std::size_t>(j + 1)] = point;
    skeleton.frames.push_back(j + 1);
    skeleton.names.push_back(joint.group);
    skeleton.bones.emplace_back(parent_point, point);
  }
  return skeleton;
}

/// The page's data: the records and how to read them.
struct PageData {
  Skeleton skeleton;
  std::vector<int> markers;  ///< model marker indices shown (the mapped ones), in model order
  std::vector<DataBlock> blocks;
  int floats_per_frame = 0;
  long frames_in_motion = 0;  ///< rows of the motion
  long frames_stored = 0;
  long stride = 1;  ///< every stride-th row is stored
  std::size_t data_limit_bytes = kDefaultDataLimitBytes;
  std::string bytes;  ///< frames_stored * floats_per_frame little-endian float32
};

namespace detail {
inline void append_float(std::string& bytes, double value) {
  const float f = static_cast<float>(value);
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  for (int shift = 0; shift < 32; shift += 8) bytes += static_cast<char>((bits >> shift) & 0xffu);
}

inline body::Pose pose_of(const io::MotionRowRef& values) { return body::pose_from_row(values); }
}  // namespace detail

/// The layout of a page's records for `model` and `mapping` (the blocks, the skeleton, the markers
/// shown), without records yet; `with_truth` adds the true skeleton's block.
inline PageData page_layout(const body::BodyModel& model, const body::MarkerMapping& mapping,
                            bool with_truth) {
  if (static_cast<int>(mapping.point_of_marker.size()) != model.marker_count())
    throw std::runtime_error("the marker mapping does not belong to the body model");
  PageData data;
  data.skeleton = skeleton_of(model);
  for (int m = 0; m < model.marker_count(); ++m)
    if (mapping.point_of_marker[static_cast<std::size_t>(m)] >= 0) data.markers.push_back(m);
  const int points = static_cast<int>(data.skeleton.frames.size());
  const int markers = static_cast<int>(data.markers.size());
  const std::vector<std::pair<std::string, int>> layout = {
      {"frame", 1},
      {"time", 1},
      {"pose", 6 + model.joint_count()},
      {"mean_marker_distance", 1},
      {"skeleton", 3 * points},
      {"model_markers", 3 * markers},
      {"recorded_markers", 3 * markers},
  };
  for (const auto& [name, count] : layout) {
    data.blocks.push_back({name, data.floats_per_frame, count});
    data.floats_per_frame += count;
  }
  if (with_truth) {
    data.blocks.push_back({"truth_skeleton", data.floats_per_frame, 3 * points});
    data.floats_per_frame += 3 * points;
  }
  return data;
}

/// Appends one frame's record (all blocks but the truth) to `bytes`: `values` the tracked row (NaN
/// when not tracked), `recorded` the frame as read (points in the recording's order).
inline void append_record(const PageData& data, const body::BodyModel& model,
                          const body::MarkerMapping& mapping, double frame_number, double time,
                          const io::MotionRowRef& values, const MarkerFrame& recorded, std::string& bytes) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const int points = static_cast<int>(data.skeleton.frames.size());
  const int markers = static_cast<int>(data.markers.size());
  Eigen::Matrix3Xd joints = Eigen::Matrix3Xd::Constant(3, points, nan);
  Eigen::Matrix3Xd model_markers = Eigen::Matrix3Xd::Constant(3, markers, nan);
  Eigen::Matrix3Xd shown = Eigen::Matrix3Xd::Constant(3, markers, nan);
  if (io::is_tracked_row(values)) {
    const body::FrameTransforms frames = body::joint_frames(model, detail::pose_of(values));
    for (int p = 0; p < points; ++p)
      joints.col(p) =
          frames.origins[static_cast<std::size_t>(data.skeleton.frames[static_cast<std::size_t>(p)])];
    const Eigen::Matrix3Xd all = body::marker_positions(model, frames);
    for (int k = 0; k < markers; ++k)
      model_markers.col(k) = all.col(data.markers[static_cast<std::size_t>(k)]);
  }
  double distance_sum = 0;
  int seen = 0;
  for (int k = 0; k < markers; ++k) {
    const int p =
        mapping.point_of_marker[static_cast<std::size_t>(data.markers[static_cast<std::size_t>(k)])];
    const bool visible =
        p < recorded.positions.cols() && recorded.visible(p) && recorded.positions.col(p).allFinite();
    if (!visible) continue;
    shown.col(k) = recorded.positions.col(p);
    if (model_markers.col(k).allFinite()) {
      distance_sum += (shown.col(k) - model_markers.col(k)).norm();
      ++seen;
    }
  }
  const auto append_points = [&](const Eigen::Matrix3Xd& positions) {
    for (Eigen::Index k = 0; k < positions.cols(); ++k)
      for (int r = 0; r < 3; ++r) detail::append_float(bytes, positions(r, k));
  };
  detail::append_float(bytes, frame_number);
  detail::append_float(bytes, time);
  for (Eigen::Index c = 0; c < values.size(); ++c) detail::append_float(bytes, values(c));
  detail::append_float(bytes, seen > 0 ? distance_sum / seen : nan);
  append_points(joints);
  append_points(model_markers);
  append_points(shown);
}

/// Builds the records. `recording` is read from its current position, one frame per motion row
/// (the rows of a tracked motion are the recording's frames in order); `truth` (same rows as the
/// motion) adds the true skeleton, posed on `model`'s bones (a truth file holds angles only).
/// Throws std::runtime_error when the motion, recording and model do not fit together.
inline PageData build_page_data(const body::BodyModel& model, const body::MarkerMapping& mapping,
                                const io::MotionTable& motion, c3d::C3dReader& recording,
                                const std::optional<io::MotionTable>& truth,
                                std::size_t data_limit_bytes = kDefaultDataLimitBytes) {
  motion.check();
  if (motion.values.cols() != 6 + model.joint_count())
    throw std::runtime_error("the motion has " + std::to_string(motion.values.cols() - 6) +
                             " joint columns, the body model " + std::to_string(model.joint_count()));
  if (motion.joint_names != model.joint_names())
    throw std::runtime_error("the motion's joint columns are not the body model's joints");
  if (motion.frames() == 0) throw std::runtime_error("the motion has no rows");
  if (truth && (truth->frames() != motion.frames() || truth->values.cols() != motion.values.cols()))
    throw std::runtime_error("the truth has " + std::to_string(truth->frames()) + " rows of " +
                             std::to_string(truth->values.cols()) + " values, the motion " +
                             std::to_string(motion.frames()) + " of " + std::to_string(motion.values.cols()));
  PageData data = page_layout(model, mapping, truth.has_value());
  const int points = static_cast<int>(data.skeleton.frames.size());

  // Decimation: the smallest stride that keeps the data within the limit.
  const std::size_t record_bytes = 4u * static_cast<std::size_t>(data.floats_per_frame);
  const auto rows = static_cast<std::size_t>(motion.frames());
  data.data_limit_bytes = data_limit_bytes;
  data.frames_in_motion = static_cast<long>(rows);
  const std::size_t fitting = std::max<std::size_t>(1, data_limit_bytes / record_bytes);
  data.stride = static_cast<long>((rows + fitting - 1) / fitting);
  data.frames_stored = static_cast<long>((rows + static_cast<std::size_t>(data.stride) - 1) /
                                         static_cast<std::size_t>(data.stride));
  data.bytes.reserve(static_cast<std::size_t>(data.frames_stored) * record_bytes);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  c3d::Frame frame;
  Eigen::Matrix3Xd truth_joints(3, points);
  for (std::size_t row = 0; row < rows; ++row) {
    if (!recording.read_frame(frame))
      throw std::runtime_error("the recording ends after " + std::to_string(row) +
                               " frames, the motion has " + std::to_string(rows) + " rows");
    if (frame.index != motion.frame[row])
      throw std::runtime_error("the motion's row " + std::to_string(row) + " is frame " +
                               std::to_string(motion.frame[row]) + ", the recording's frame there is " +
                               std::to_string(frame.index));
    if (row % static_cast<std::size_t>(data.stride) != 0) continue;
    const Eigen::Index r = static_cast<Eigen::Index>(row);
    const io::MotionRowRef values = motion.values.row(r).transpose();
    append_record(data, model, mapping, static_cast<double>(motion.frame[row]), motion.time[row], values,
                  frame, data.bytes);
    if (truth) {
      truth_joints.setConstant(nan);
      const io::MotionRowRef true_values = truth->values.row(r).transpose();
      if (io::is_tracked_row(true_values)) {
        const body::FrameTransforms frames = body::joint_frames(model, detail::pose_of(true_values));
        for (int p = 0; p < points; ++p)
          truth_joints.col(p) =
              frames.origins[static_cast<std::size_t>(data.skeleton.frames[static_cast<std::size_t>(p)])];
      }
      for (int p = 0; p < points; ++p)
        for (int c = 0; c < 3; ++c) detail::append_float(data.bytes, truth_joints(c, p));
    }
  }
  return data;
}

}  // namespace s2kf::cli::viewer
