/// @file
/// Writing a body model as an OpenSim 4 model file (.osim): bodies, joints whose coordinates carry
/// the names, ranges and default values of the .mot columns, and a MarkerSet, so that OpenSim's
/// "Load Motion" plays the tracker's .mot and its Inverse Kinematics tool runs on the .trc markers.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/atomic_file.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::io {

/// OpenSim's ground is Y-up with X forward, the model's (and the C3D lab's) frame Z-up with x to the
/// subject's right and y forward. A lab vector v is (v_y, v_z, v_x) in OpenSim's ground: a proper
/// rotation (a cyclic permutation), written into the .osim as the orientation of the frame the root
/// joint hangs from and applied to the .trc markers, so the .mot's root_x/y/z stay lab coordinates.
inline Eigen::Matrix3d opensim_ground_from_lab() {
  Eigen::Matrix3d rotation;
  rotation << 0, 1, 0,  //
      0, 0, 1,          //
      1, 0, 0;
  return rotation;
}

/// opensim_ground_from_lab() as the body-fixed X-Y-Z Euler angles (rad) OpenSim's PhysicalOffsetFrame
/// takes: Rx(-pi/2) * Ry(0) * Rz(-pi/2).
inline Eigen::Vector3d opensim_ground_from_lab_xyz_euler() {
  const double half_pi = 1.57079632679489661923;
  return {-half_pi, 0.0, -half_pi};
}

namespace detail {

/// One OpenSim body: the model frames from `first_joint` to `last_joint` (consecutive DoFs of one
/// group, at most 3) collapse into one CustomJoint whose child is this body.
struct OsimBody {
  std::string name;
  int first_joint = -1;  ///< -1: the root (pelvis)
  int last_joint = -1;
  int parent_body = -1;  ///< index into the body list; -1: ground
};

/// Splits the model's joint chain into bodies. A model frame needs its own body when it ends a group,
/// when a marker rides on it (the elbow's flexion-only frame carries LAOL/RAOL) or when another
/// group hangs from it; the DoFs between two such frames share one CustomJoint (R = R1 R2 R3 in the
/// order the model composes them).
inline std::vector<OsimBody> osim_bodies(const body::BodyModel& model) {
  std::vector<bool> needs_body(model.frame_count(), false);
  for (const body::Marker& marker : model.markers) needs_body[marker.frame] = true;
  for (int j = 0; j < model.joint_count(); ++j) {
    const body::Joint& joint = model.joints[j];
    const bool continued = j + 1 < model.joint_count() && model.joints[j + 1].parent_frame == j + 1 &&
                           model.joints[j + 1].group == joint.group &&
                           model.joints[j + 1].translation.isZero(0);
    if (!continued) needs_body[j + 1] = true;
    if (joint.parent_frame > 0 && model.joints[joint.parent_frame - 1].group != joint.group)
      needs_body[joint.parent_frame] = true;
  }
  std::vector<OsimBody> bodies{{"pelvis", -1, -1, -1}};
  std::vector<int> body_of_frame(model.frame_count(), -1);
  body_of_frame[0] = 0;
  int start = 0;  // first joint of the body being collected
  for (int j = 0; j < model.joint_count(); ++j) {
    // Joint j continues the chain only when it hangs from the previous DoF and that DoF ended no body.
    if (model.joints[j].parent_frame != j || needs_body[j]) start = j;
    if (!needs_body[j + 1]) continue;
    if (j - start + 1 > 3)
      throw std::invalid_argument("OpenSim model: joint " + model.joints[j].name +
                                  " would need more than 3 rotations in one CustomJoint");
    OsimBody body;
    const bool ends_group =
        j + 1 >= model.joint_count() || model.joints[j + 1].group != model.joints[j].group;
    body.name = ends_group ? model.joints[j].group : model.joints[j].name + "_frame";
    body.first_joint = start;
    body.last_joint = j;
    body.parent_body = body_of_frame[model.joints[start].parent_frame];
    if (body.parent_body < 0)
      throw std::invalid_argument("OpenSim model: joint " + model.joints[start].name +
                                  " hangs from a frame without a body");
    body_of_frame[j + 1] = static_cast<int>(bodies.size());
    bodies.push_back(body);
  }
  for (const body::Marker& marker : model.markers)
    if (body_of_frame[marker.frame] < 0)
      throw std::invalid_argument("OpenSim model: marker " + marker.name + " rides on no body");
  return bodies;
}

inline std::string osim_vector(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s << std::setprecision(12) << v.x() << " " << v.y() << " " << v.z();
  return s.str();
}

inline std::string osim_axis(body::Axis axis) {
  return osim_vector(Eigen::Vector3d::Unit(static_cast<int>(axis)));
}

/// A TransformAxis driven one-to-one by a coordinate, or held at 0 (empty coordinate).
inline void write_transform_axis(std::ostream& out, const std::string& name, const std::string& coordinate,
                                 const Eigen::Vector3d& axis, const std::string& pad) {
  out << pad << "<TransformAxis name=\"" << name << "\">\n"
      << pad << "  <coordinates>" << coordinate << "</coordinates>\n"
      << pad << "  <axis>" << osim_vector(axis) << "</axis>\n";
  if (coordinate.empty())
    out << pad << "  <Constant name=\"function\">\n"
        << pad << "    <value>0</value>\n"
        << pad << "  </Constant>\n";
  else
    out << pad << "  <LinearFunction name=\"function\">\n"
        << pad << "    <coefficients>1 0</coefficients>\n"
        << pad << "  </LinearFunction>\n";
  out << pad << "</TransformAxis>\n";
}

inline void write_coordinate(std::ostream& out, const std::string& name, double default_value, double lower,
                             double upper, bool clamped, const std::string& pad) {
  out << std::setprecision(12) << pad << "<Coordinate name=\"" << name << "\">\n"
      << pad << "  <default_value>" << default_value << "</default_value>\n"
      << pad << "  <default_speed_value>0</default_speed_value>\n"
      << pad << "  <range>" << lower << " " << upper << "</range>\n"
      << pad << "  <clamped>" << (clamped ? "true" : "false") << "</clamped>\n"
      << pad << "  <locked>false</locked>\n"
      << pad << "</Coordinate>\n";
}

inline void write_offset_frame(std::ostream& out, const std::string& name, const std::string& parent_path,
                               const Eigen::Vector3d& translation_m, const Eigen::Vector3d& orientation_xyz,
                               const std::string& pad) {
  out << pad << "<PhysicalOffsetFrame name=\"" << name << "\">\n"
      << pad << "  <socket_parent>" << parent_path << "</socket_parent>\n"
      << pad << "  <translation>" << osim_vector(translation_m) << "</translation>\n"
      << pad << "  <orientation>" << osim_vector(orientation_xyz) << "</orientation>\n"
      << pad << "</PhysicalOffsetFrame>\n";
}

inline std::string xml_escaped(const std::string& text) {
  std::string escaped;
  for (const char c : text) switch (c) {
      case '&':
        escaped += "&amp;";
        break;
      case '<':
        escaped += "&lt;";
        break;
      case '>':
        escaped += "&gt;";
        break;
      case '"':
        escaped += "&quot;";
        break;
      default:
        escaped += c;
    }
  return escaped;
}

}  // namespace detail

/// Root translations beyond this (m) are outside any motion capture volume.
inline constexpr double kOpenSimRootTranslationRangeM = 50.0;

/// Inertial properties are not estimated (markers do not measure them); OpenSim's multibody engine
/// needs a positive mass on every body, so each gets this placeholder, which the .osim says in its
/// <credits>. Kinematics (Load Motion, Inverse Kinematics) do not use it; inverse dynamics needs
/// real segment masses (OpenSim's Scale tool or a hand edit).
inline constexpr double kOpenSimPlaceholderMassKg = 1.0;
inline constexpr double kOpenSimPlaceholderInertiaKgM2 = 0.01;

/// The .osim of `model` (metres, radians). Coordinates: root_x, root_y, root_z (m, lab frame), root_roll,
/// root_pitch, root_yaw (rad, R = Rz(yaw) Ry(pitch) Rx(roll)) on a 6-DoF CustomJoint "ground_pelvis",
/// and one coordinate per model joint under its own name with its limits as range (clamped); the
/// defaults are the zero pose standing on the floor (root_z = the height of the root above the lowest
/// marker). The MarkerSet holds the markers named in `marker_names` (all of the model's when empty)
/// at their offsets on their bodies.
void write_opensim_model(std::ostream& out, const body::BodyModel& model, const std::string& name,
                         const std::vector<std::string>& marker_names = {});

void save_opensim_model(const std::string& path, const body::BodyModel& model, const std::string& name,
                        const std::vector<std::string>& marker_names = {});

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

S2KF_INLINE void write_opensim_model(std::ostream& out, const body::BodyModel& model, const std::string& name,
                                     const std::vector<std::string>& marker_names) {
  model.validate();
  const std::vector<detail::OsimBody> bodies = detail::osim_bodies(model);
  std::vector<int> body_of_frame(model.frame_count(), -1);
  body_of_frame[0] = 0;
  for (std::size_t b = 1; b < bodies.size(); ++b)
    body_of_frame[bodies[b].last_joint + 1] = static_cast<int>(b);
  for (const std::string& marker : marker_names)
    if (model.marker_index(marker) < 0)
      throw std::invalid_argument("OpenSim model: no marker " + marker + " in the body model");

  // Standing on the floor by default: the lowest marker of the zero pose at z = 0.
  double standing_root_z_m = 0;
  if (model.marker_count() > 0) {
    const Eigen::Matrix3Xd zero_pose =
        body::marker_positions(model, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(),
                               Eigen::VectorXd::Zero(model.joint_count()));
    standing_root_z_m = -zero_pose.row(2).minCoeff() / 1000.0;
  }
  const double pi = 3.14159265358979323846;
  const std::string p6(6, ' '), p8(8, ' '), p10(10, ' '), p12(12, ' ');

  out << "<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n"
      << "<OpenSimDocument Version=\"40000\">\n"
      << "  <Model name=\"" << detail::xml_escaped(name) << "\">\n"
      << "    <credits>Written by s2kf: the " << model.joint_count()
      << "-joint MMM-style body model at the subject's calibrated bone lengths. Masses and inertias are "
         "placeholders ("
      << kOpenSimPlaceholderMassKg << " kg, " << kOpenSimPlaceholderInertiaKgM2
      << " kg m^2 per body), not estimates.</credits>\n"
      << "    <publications>Terlemez et al., Master Motor Map (MMM), Humanoids 2014</publications>\n"
      << "    <length_units>meters</length_units>\n"
      << "    <force_units>N</force_units>\n"
      << "    <gravity>0 -9.80665 0</gravity>\n"
      << "    <Ground name=\"ground\" />\n"
      << "    <BodySet name=\"bodyset\">\n      <objects>\n";
  for (const detail::OsimBody& body : bodies)
    out << p8 << "<Body name=\"" << body.name << "\">\n"
        << p10 << "<mass>" << kOpenSimPlaceholderMassKg << "</mass>\n"
        << p10 << "<mass_center>0 0 0</mass_center>\n"
        << p10 << "<inertia>" << kOpenSimPlaceholderInertiaKgM2 << " " << kOpenSimPlaceholderInertiaKgM2
        << " " << kOpenSimPlaceholderInertiaKgM2 << " 0 0 0</inertia>\n"
        << p8 << "</Body>\n";
  out << "      </objects>\n    </BodySet>\n"
      << "    <JointSet name=\"jointset\">\n      <objects>\n";

  // The root: rotations about z, y, x (body-fixed: Rz Ry Rx), then translations along the lab axes.
  out << p8 << "<CustomJoint name=\"ground_pelvis\">\n"
      << p10 << "<socket_parent_frame>ground_offset</socket_parent_frame>\n"
      << p10 << "<socket_child_frame>pelvis_offset</socket_child_frame>\n"
      << p10 << "<coordinates>\n";
  const char* const root_axes = "xyz";
  for (int k = 0; k < 3; ++k)
    detail::write_coordinate(out, std::string("root_") + root_axes[k], k == 2 ? standing_root_z_m : 0.0,
                             -kOpenSimRootTranslationRangeM, kOpenSimRootTranslationRangeM, false, p12);
  detail::write_coordinate(out, "root_roll", 0, -pi, pi, false, p12);
  detail::write_coordinate(out, "root_pitch", 0, -pi / 2, pi / 2, false, p12);
  detail::write_coordinate(out, "root_yaw", 0, -pi, pi, false, p12);
  out << p10 << "</coordinates>\n" << p10 << "<frames>\n";
  detail::write_offset_frame(out, "ground_offset", "/ground", Eigen::Vector3d::Zero(),
                             opensim_ground_from_lab_xyz_euler(), p12);
  detail::write_offset_frame(out, "pelvis_offset", "/bodyset/pelvis", Eigen::Vector3d::Zero(),
                             Eigen::Vector3d::Zero(), p12);
  out << p10 << "</frames>\n" << p10 << "<SpatialTransform>\n";
  detail::write_transform_axis(out, "rotation1", "root_yaw", Eigen::Vector3d::UnitZ(), p12);
  detail::write_transform_axis(out, "rotation2", "root_pitch", Eigen::Vector3d::UnitY(), p12);
  detail::write_transform_axis(out, "rotation3", "root_roll", Eigen::Vector3d::UnitX(), p12);
  for (int k = 0; k < 3; ++k)
    detail::write_transform_axis(out, "translation" + std::to_string(k + 1),
                                 std::string("root_") + root_axes[k], Eigen::Vector3d::Unit(k), p12);
  out << p10 << "</SpatialTransform>\n" << p8 << "</CustomJoint>\n";

  for (std::size_t b = 1; b < bodies.size(); ++b) {
    const detail::OsimBody& body = bodies[b];
    const std::string& parent = bodies[body.parent_body].name;
    out << p8 << "<CustomJoint name=\"" << body.name << "_joint\">\n"
        << p10 << "<socket_parent_frame>" << parent << "_offset</socket_parent_frame>\n"
        << p10 << "<socket_child_frame>" << body.name << "_offset</socket_child_frame>\n"
        << p10 << "<coordinates>\n";
    for (int j = body.first_joint; j <= body.last_joint; ++j) {
      const body::Joint& joint = model.joints[j];
      detail::write_coordinate(out, joint.name, std::clamp(0.0, joint.lower, joint.upper), joint.lower,
                               joint.upper, true, p12);
    }
    out << p10 << "</coordinates>\n" << p10 << "<frames>\n";
    detail::write_offset_frame(out, parent + "_offset", "/bodyset/" + parent,
                               model.joints[body.first_joint].translation / 1000.0, Eigen::Vector3d::Zero(),
                               p12);
    detail::write_offset_frame(out, body.name + "_offset", "/bodyset/" + body.name, Eigen::Vector3d::Zero(),
                               Eigen::Vector3d::Zero(), p12);
    out << p10 << "</frames>\n" << p10 << "<SpatialTransform>\n";
    // The joint's DoFs in order, then the remaining axes held at 0 (OpenSim wants three independent
    // rotation axes).
    std::vector<bool> axis_used(3, false);
    int slot = 1;
    for (int j = body.first_joint; j <= body.last_joint; ++j, ++slot) {
      axis_used[static_cast<int>(model.joints[j].axis)] = true;
      detail::write_transform_axis(out, "rotation" + std::to_string(slot), model.joints[j].name,
                                   Eigen::Vector3d::Unit(static_cast<int>(model.joints[j].axis)), p12);
    }
    for (int k = 0; k < 3; ++k)
      if (!axis_used[k])
        detail::write_transform_axis(out, "rotation" + std::to_string(slot++), "", Eigen::Vector3d::Unit(k),
                                     p12);
    for (int k = 0; k < 3; ++k)
      detail::write_transform_axis(out, "translation" + std::to_string(k + 1), "", Eigen::Vector3d::Unit(k),
                                   p12);
    out << p10 << "</SpatialTransform>\n" << p8 << "</CustomJoint>\n";
  }
  out << "      </objects>\n    </JointSet>\n"
      << "    <MarkerSet name=\"markerset\">\n      <objects>\n";
  for (const body::Marker& marker : model.markers) {
    if (!marker_names.empty() &&
        std::find(marker_names.begin(), marker_names.end(), marker.name) == marker_names.end())
      continue;
    out << p8 << "<Marker name=\"" << detail::xml_escaped(marker.name) << "\">\n"
        << p10 << "<socket_parent_frame>/bodyset/" << bodies[body_of_frame[marker.frame]].name
        << "</socket_parent_frame>\n"
        << p10 << "<location>" << detail::osim_vector(marker.offset / 1000.0) << "</location>\n"
        << p10 << "<fixed>true</fixed>\n"
        << p8 << "</Marker>\n";
  }
  out << "      </objects>\n    </MarkerSet>\n  </Model>\n</OpenSimDocument>\n";
}

S2KF_INLINE void save_opensim_model(const std::string& path, const body::BodyModel& model,
                                    const std::string& name, const std::vector<std::string>& marker_names) {
  write_file_atomically(path,
                        [&](std::ostream& out) { write_opensim_model(out, model, name, marker_names); });
}

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::io
