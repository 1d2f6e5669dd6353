/// @file
/// Writing a body model as an OpenSim 4 model file (.osim): bodies, joints whose coordinates carry
/// the names, ranges and default values of the .mot columns, and a MarkerSet, so that OpenSim's
/// "Load Motion" plays the tracker's .mot and its Inverse Kinematics tool runs on the .trc markers.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/segment_inertia.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/atomic_file.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
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

/// `left_open`: without the closing tag, for the caller to add children (attached geometry).
inline void write_offset_frame(std::ostream& out, const std::string& name, const std::string& parent_path,
                               const Eigen::Vector3d& translation_m, const Eigen::Vector3d& orientation_xyz,
                               const std::string& pad, bool left_open = false) {
  out << pad << "<PhysicalOffsetFrame name=\"" << name << "\">\n"
      << pad << "  <socket_parent>" << parent_path << "</socket_parent>\n"
      << pad << "  <translation>" << osim_vector(translation_m) << "</translation>\n"
      << pad << "  <orientation>" << osim_vector(orientation_xyz) << "</orientation>\n";
  if (!left_open) out << pad << "</PhysicalOffsetFrame>\n";
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

/// A body no segment of de Leva's table rides on (the neck's BLN, the elbow's flexion-only frame):
/// no mass, no inertia. Simbody accepts massless bodies that have a massive body beyond them.
inline constexpr double kOpenSimMasslessKg = 0.0;

namespace detail {

/// The semi-axes (mm) of the ellipsoid drawn for a segment: half its length along its long axis,
/// and across it those of the uniform solid ellipsoid with the segment's moments of inertia
/// (a_x^2 = 5 (I_y + I_z - I_x) / (2 m), ...), at least a tenth of the length.
inline Eigen::Vector3d segment_ellipsoid_radii_mm(const body::SegmentInertia& segment) {
  const Eigen::Vector3d axis = segment.distal_mm - segment.proximal_mm;
  const double length_mm = axis.norm();
  Eigen::Vector3d radii;
  int long_axis = 0;
  axis.cwiseAbs().maxCoeff(&long_axis);
  const Eigen::Vector3d& moments = segment.moments_kg_m2;
  for (int k = 0; k < 3; ++k) {
    const double squared_m2 =
        2.5 * (moments((k + 1) % 3) + moments((k + 2) % 3) - moments(k)) / segment.mass_kg;
    radii(k) = std::max(1000.0 * std::sqrt(std::max(squared_m2, 0.0)), 0.1 * length_mm);
  }
  radii(long_axis) = 0.5 * length_mm;
  return radii;
}

}  // namespace detail

/// The .osim of `model` (metres, radians, kilograms). Coordinates: root_x, root_y, root_z (m, lab frame),
/// root_roll, root_pitch, root_yaw (rad, R = Rz(yaw) Ry(pitch) Rx(roll)) on a 6-DoF CustomJoint
/// "ground_pelvis", and one coordinate per model joint under its own name with its limits as range (clamped);
/// the defaults are the zero pose standing on the floor (root_z = the height of the root above the lowest
/// marker). The MarkerSet holds the markers named in `marker_names` (all of the model's when empty)
/// at their offsets on their bodies. Bodies carry de Leva's segment masses and inertias for a subject
/// of `body_mass_kg` (0: body::default_body_mass_kg of the model's height) and an ellipsoid of the
/// segment's size (OpenSim's analytic geometry, no mesh files) so that the GUI shows the skeleton.
void write_opensim_model(std::ostream& out, const body::BodyModel& model, const std::string& name,
                         const std::vector<std::string>& marker_names = {}, double body_mass_kg = 0);

void save_opensim_model(const std::string& path, const body::BodyModel& model, const std::string& name,
                        const std::vector<std::string>& marker_names = {}, double body_mass_kg = 0);

}  // namespace s2kf::io

#if !defined(S2KF_COMPILED)
#include <s2kf/io/opensim_model.hxx>
#endif
