/// @file
/// The definitions of <s2kf/io/opensim_model.hpp>: inline where the library is used header-only, compiled
/// once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/io/opensim_model.hpp>

namespace s2kf::io {

S2KF_INLINE void write_opensim_model(std::ostream& out, const body::BodyModel& model, const std::string& name,
                                     const std::vector<std::string>& marker_names, double body_mass_kg) {
  model.validate();
  if (body_mass_kg == 0) body_mass_kg = body::default_body_mass_kg(model.height_mm);
  const std::vector<body::SegmentInertia> inertia = body::de_leva_segment_inertia(model, body_mass_kg);
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
      << "-joint MMM-style body model at the subject's calibrated bone lengths. Segment masses, centres of "
         "mass and inertias: de Leva (1996) for a body mass of "
      << std::setprecision(6) << body_mass_kg << " kg, not estimated from the motion.</credits>\n"
      << "    <publications>Terlemez et al., Master Motor Map (MMM), Humanoids 2014; de Leva, Adjustments to "
         "Zatsiorsky-Seluyanov's segment inertia parameters, J. Biomech. 29(9), 1996</publications>\n"
      << "    <length_units>meters</length_units>\n"
      << "    <force_units>N</force_units>\n"
      << "    <gravity>0 -9.80665 0</gravity>\n"
      << "    <Ground name=\"ground\" />\n"
      << "    <BodySet name=\"bodyset\">\n      <objects>\n";
  for (const detail::OsimBody& body : bodies) {
    const std::string segment = body.first_joint < 0 ? std::string("root") : body.name;
    const auto found = std::find_if(inertia.begin(), inertia.end(),
                                    [&](const body::SegmentInertia& s) { return s.segment == segment; });
    out << p8 << "<Body name=\"" << body.name << "\">\n";
    if (found == inertia.end()) {
      out << p10 << "<mass>" << kOpenSimMasslessKg << "</mass>\n"
          << p10 << "<mass_center>0 0 0</mass_center>\n"
          << p10 << "<inertia>0 0 0 0 0 0</inertia>\n"
          << p8 << "</Body>\n";
      continue;
    }
    // An ellipsoid on an offset frame at the middle of the segment, axes along the body's.
    out << p10 << "<components>\n";
    detail::write_offset_frame(out, body.name + "_geometry_frame", "..",
                               0.5 * (found->proximal_mm + found->distal_mm) / 1000.0,
                               Eigen::Vector3d::Zero(), p12, true);
    out << p12 << "  <attached_geometry>\n"
        << p12 << "    <Ellipsoid name=\"" << body.name << "_geometry\">\n"
        << p12 << "      <socket_frame>..</socket_frame>\n"
        << p12 << "      <radii>" << detail::osim_vector(detail::segment_ellipsoid_radii_mm(*found) / 1000.0)
        << "</radii>\n"
        << p12 << "    </Ellipsoid>\n"
        << p12 << "  </attached_geometry>\n"
        << p12 << "</PhysicalOffsetFrame>\n"
        << p10 << "</components>\n"
        << p10 << "<mass>" << std::setprecision(12) << found->mass_kg << "</mass>\n"
        << p10 << "<mass_center>" << detail::osim_vector(found->centre_of_mass_mm / 1000.0)
        << "</mass_center>\n"
        << p10 << "<inertia>" << detail::osim_vector(found->moments_kg_m2) << " 0 0 0</inertia>\n"
        << p8 << "</Body>\n";
  }
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
                                    const std::string& name, const std::vector<std::string>& marker_names,
                                    double body_mass_kg) {
  write_file_atomically(
      path, [&](std::ostream& out) { write_opensim_model(out, model, name, marker_names, body_mass_kg); });
}

}  // namespace s2kf::io
