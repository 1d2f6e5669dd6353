/// @file
/// s2kf.BodyModel: the 40-joint, 50-marker MMM-style model, its tables, and forward kinematics of a
/// batch of poses (F, 46) -> markers (F, 50, 3) through the library's blocked, vectorised kernel.
#include "bindings.hpp"
#include "numpy_bridge.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/pose.hpp>

#include <pybind11/stl.h>

#include <string>
#include <vector>

namespace s2kf::python {
namespace {

/// Marker positions of poses given as rows [root x, y, z (mm), roll, pitch, yaw (rad), 40 joint
/// angles (rad)], the tracker's motion columns. (46,) -> (M, 3); (F, 46) -> (F, M, 3).
py::array_t<double> marker_positions(const body::BodyModel& model, const py::handle& poses_value) {
  const DoubleArray poses = as_double_array(poses_value, "poses");
  const py::ssize_t columns = 6 + model.joint_count();
  const std::string form = "(" + std::to_string(columns) + ",) or (F, " + std::to_string(columns) + ")";
  const bool single = poses.ndim() == 1;
  if (single)
    require_shape(poses, {columns}, "poses", form);
  else
    require_shape(poses, {-1, columns}, "poses", form);
  const Eigen::Index count = single ? 1 : poses.shape(0);
  const Eigen::Index markers = model.marker_count();
  py::array_t<double> out = single ? py::array_t<double>({markers, Eigen::Index{3}})
                                   : py::array_t<double>({count, markers, Eigen::Index{3}});
  // C-ordered (F, 46) is a column-major 46 x F matrix (one pose per column), and C-ordered
  // (F, M, 3) the 3M x F marker block marker_positions_batch writes: both are used in place.
  const Eigen::Map<const Eigen::MatrixXd> pose_columns(poses.data(), columns, count);
  Eigen::Map<Eigen::MatrixXd> marker_columns(out.mutable_data(), 3 * markers, count);
  {
    py::gil_scoped_release unlocked;
    Eigen::MatrixXd rotations(9, count);
    for (Eigen::Index i = 0; i < count; ++i) {
      const Eigen::Matrix3d r = body::rotation_from_rpy(pose_columns.col(i).segment<3>(3));
      for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 3; ++col) rotations(3 * row + col, i) = r(row, col);
    }
    body::ForwardKinematicsWorkspace workspace;
    body::marker_positions_batch(model, pose_columns.topRows(3), rotations,
                                 pose_columns.bottomRows(model.joint_count()), workspace, marker_columns);
  }
  return out;
}

py::array_t<double> marker_offsets(const body::BodyModel& model) {
  Eigen::Matrix3Xd offsets(3, model.marker_count());
  for (int m = 0; m < model.marker_count(); ++m) offsets.col(m) = model.markers[m].offset;
  return points_copy(offsets);
}

}  // namespace

void bind_body(py::module_& module) {
  module.attr("JOINT_COUNT") = body::kJointCount;
  module.attr("STATE_DIMENSION") = body::kStateDimension;
  module.def(
      "pose_columns",
      [](const body::BodyModel& model) {
        std::vector<std::string> columns{"root_x", "root_y", "root_z", "root_roll", "root_pitch", "root_yaw"};
        for (const body::Joint& joint : model.joints) columns.push_back(joint.name);
        return columns;
      },
      py::arg("model"), "names of the 46 pose columns: root_x..root_yaw, then the joints");

  py::class_<body::BodyModel>(module, "BodyModel",
                              "The MMM-style body model: 40 joints with limits, 50 markers. Lengths in mm, "
                              "angles in rad; x = the subject's right, y = forward, z = up.")
      .def(py::init([](double height_mm) {
             if (!(height_mm > 0) || !std::isfinite(height_mm))
               throw py::value_error("the body height must be a positive number of mm, got " +
                                     std::to_string(height_mm));
             return body::mmm_body_model(height_mm);
           }),
           py::arg("height_mm") = 1750.0, "the model scaled to a subject of this height")
      .def_readonly("height_mm", &body::BodyModel::height_mm)
      .def_property_readonly("joint_count", &body::BodyModel::joint_count)
      .def_property_readonly("marker_count", &body::BodyModel::marker_count)
      .def_property_readonly("joint_names", &body::BodyModel::joint_names)
      .def_property_readonly("marker_names", &body::BodyModel::marker_names)
      .def_property_readonly(
          "lower_limits", [](const body::BodyModel& m) { return vector_copy(m.lower_limits()); }, "rad")
      .def_property_readonly(
          "upper_limits", [](const body::BodyModel& m) { return vector_copy(m.upper_limits()); }, "rad")
      .def_property_readonly(
          "marker_frames",
          [](const body::BodyModel& m) {
            std::vector<std::string> frames;
            for (const body::Marker& marker : m.markers) frames.push_back(m.frame_name(marker.frame));
            return frames;
          },
          "the frame (root or joint name) each marker rides on")
      .def_property_readonly("marker_offsets", &marker_offsets, "(M, 3) mm, each in its frame")
      .def("scaled", &body::BodyModel::scaled, py::arg("height_mm"),
           "the same body at another height: every length scaled")
      .def("marker_positions", &marker_positions, py::arg("poses"),
           "Forward kinematics: poses (46,) or (F, 46) [root x, y, z mm, roll, pitch, yaw rad, 40 joint "
           "angles rad] -> markers (M, 3) or (F, M, 3) in mm. Runs without the GIL.")
      .def("__repr__", [](const body::BodyModel& m) {
        return "<s2kf.BodyModel: " + std::to_string(m.joint_count()) + " joints, " +
               std::to_string(m.marker_count()) + " markers, height " +
               std::to_string(static_cast<long>(std::lround(m.height_mm))) + " mm>";
      });
}

}  // namespace s2kf::python
