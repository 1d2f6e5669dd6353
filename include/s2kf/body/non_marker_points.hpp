/// @file
/// Points a recording holds that are no markers on the skin, told by their labels: what capture
/// software computes and stores as points (joint angles, forces, moments, powers, joint centres,
/// centres of mass, Plug-in Gait's segment axes). They are never tracked or inferred as markers.
/// (Points listed in a C3D file's POINT:ANGLES/FORCES/MOMENTS/POWERS parameters are recognised by
/// the reader already: io/c3d_reader.hpp, `PointLabel::model_output`.)
#pragma once

#include <s2kf/body/label_text.hpp>

#include <algorithm>
#include <array>
#include <optional>
#include <string>
#include <vector>

namespace s2kf::body {

namespace detail {

inline bool ends_with(const std::string& text, const std::string& tail) {
  return text.size() >= tail.size() && text.compare(text.size() - tail.size(), tail.size(), tail) == 0;
}

inline bool starts_with(const std::string& text, const std::string& head) {
  return text.compare(0, head.size(), head) == 0;
}

}  // namespace detail

/// Why the point labelled `label` is no marker, or nothing when its label says it may be one.
/// `labels`: all of the recording's labels (a Plug-in Gait segment axis is recognised by its
/// quartet: PELO, PELA, PELL and PELP all present; PELA alone may be a cluster marker).
/// Recognised, case and subject prefix ignored:
/// - model outputs by their Vicon names: ...Angle(s), ...Force(s), ...Moment(s), ...Power(s),
///   ...GRF, ...NRM;
/// - joint centres: ...JC (LHJC, RKJC, L_HJC), ..._JC, ...JointCentre / ...JointCenter;
/// - virtual points of Motion Analysis' software: V_... (V_Mid_ASIS, V_R.Hip_JC);
/// - centres of mass: CentreOfMass..., CenterOfMass..., COM, ...COM;
/// - Plug-in Gait segment axes: NAMEO, NAMEA, NAMEL, NAMEP, all four present.
inline std::optional<std::string> non_marker_reason(const std::string& label,
                                                    const std::vector<std::string>& labels) {
  const std::string name = upper_case(trim(strip_subject_prefix(label)));
  if (name.empty()) return std::nullopt;
  using detail::ends_with;
  using detail::starts_with;
  for (const char* kind : {"ANGLE", "ANGLES", "FORCE", "FORCES", "MOMENT", "MOMENTS", "POWER", "POWERS"})
    if (ends_with(name, kind) && name.size() > std::string(kind).size())
      return std::string("a model output (") +
             (kind[0] == 'A'   ? "joint angles"
              : kind[0] == 'F' ? "forces"
              : kind[0] == 'M' ? "moments"
                               : "powers") +
             " stored as a point), no marker";
  if (ends_with(name, "GRF") || ends_with(name, "NRM"))
    return std::string("a model output (ground reaction) stored as a point, no marker");
  if ((ends_with(name, "JC") && name.size() >= 3 && name.size() <= 6) || ends_with(name, "_JC") ||
      ends_with(name, ".JC") || ends_with(name, "JOINTCENTRE") || ends_with(name, "JOINTCENTER") ||
      ends_with(name, "JOINT_CENTRE") || ends_with(name, "JOINT_CENTER"))
    return std::string("a joint centre computed by the capture software, no marker");
  if (starts_with(name, "V_"))
    return std::string("a virtual point of the capture software (V_ prefix), no marker");
  if (starts_with(name, "CENTREOFMASS") || starts_with(name, "CENTEROFMASS") || name == "COM" ||
      ends_with(name, "_COM"))
    return std::string("a centre of mass computed by the capture software, no marker");
  if (name.size() >= 4) {
    const std::string stem = name.substr(0, name.size() - 1);
    const char last = name.back();
    if (last == 'O' || last == 'A' || last == 'L' || last == 'P') {
      const auto present = [&](char axis) {
        return std::any_of(labels.begin(), labels.end(), [&](const std::string& other) {
          return upper_case(trim(strip_subject_prefix(other))) == stem + axis;
        });
      };
      if (present('O') && present('A') && present('L') && present('P'))
        return "a segment axis point of Plug-in Gait (" + stem +
               "O/A/L/P: origin, anterior, lateral, "
               "proximal), no marker";
    }
  }
  return std::nullopt;
}

}  // namespace s2kf::body
