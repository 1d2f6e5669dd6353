/// @file
/// Segment masses, centres of mass and moments of inertia of the body model for a subject's body
/// mass, from de Leva's adjustment of Zatsiorsky and Seluyanov's parameters (P. de Leva, "Adjustments
/// to Zatsiorsky-Seluyanov's segment inertia parameters", J. Biomech. 29(9):1223-1230, 1996, table 4,
/// male). Markers do not measure inertia: these are the published averages placed on the model's
/// bones, what an OpenSim model needs before inverse dynamics.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::body {

/// de Leva's male reference subject: 73.0 kg at 1741 mm, the stature his segment lengths belong to.
inline constexpr double kDeLevaStatureMm = 1741.0;
inline constexpr double kDeLevaBodyMassKg = 73.0;

/// The body mass assumed when none is given: de Leva's reference subject's body mass index
/// (73.0 kg / 1.741^2 m^2 = 24.1 kg/m^2) at the subject's height.
inline double default_body_mass_kg(double height_mm) {
  const double ratio = height_mm / kDeLevaStatureMm;
  return kDeLevaBodyMassKg * ratio * ratio;
}

/// One segment's inertial parameters, in the frame of the model segment that carries it.
struct SegmentInertia {
  std::string segment;  ///< "root" or a joint group ("BP", "LK", ...)
  double mass_kg = 0;
  Eigen::Vector3d centre_of_mass_mm = Eigen::Vector3d::Zero();
  /// About axes through the centre of mass parallel to the frame's x (right), y (forward), z (up).
  Eigen::Vector3d moments_kg_m2 = Eigen::Vector3d::Zero();
  /// The ends of de Leva's segment (proximal, distal), for drawing it.
  Eigen::Vector3d proximal_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d distal_mm = Eigen::Vector3d::Zero();
};

namespace detail {

/// A row of de Leva's table 4 (male): mass fraction, centre of mass as a fraction of the length from
/// the proximal end, radii of gyration as fractions of the length about the sagittal (antero-posterior),
/// transverse (medio-lateral) and longitudinal axes, and the segment length (mm at 1741 mm stature).
struct DeLevaRow {
  double mass, centre, r_sagittal, r_transverse, r_longitudinal, length_mm;
};

inline constexpr DeLevaRow kDeLevaHeadNeck{0.0694, 0.5002, 0.303, 0.315, 0.261, 242.9};  // vertex to C7
inline constexpr DeLevaRow kDeLevaUpperTrunk{0.1596, 0.2999, 0.716, 0.454, 0.659, 170.7};
inline constexpr DeLevaRow kDeLevaMiddleTrunk{0.1633, 0.4502, 0.482, 0.383, 0.468, 215.5};
inline constexpr DeLevaRow kDeLevaLowerTrunk{0.1117, 0.6115, 0.615, 0.551, 0.587, 145.7};
inline constexpr DeLevaRow kDeLevaUpperArm{0.0271, 0.5772, 0.285, 0.269, 0.158, 281.7};
inline constexpr DeLevaRow kDeLevaForearm{0.0162, 0.4574, 0.276, 0.265, 0.121, 268.9};
inline constexpr DeLevaRow kDeLevaHand{0.0061, 0.7900, 0.628, 0.513, 0.401, 86.2};  // wrist to MCP III
inline constexpr DeLevaRow kDeLevaThigh{0.1416, 0.4095, 0.329, 0.329, 0.149, 422.2};
inline constexpr DeLevaRow kDeLevaShank{0.0433, 0.4459, 0.255, 0.249, 0.103, 434.0};
inline constexpr DeLevaRow kDeLevaFoot{0.0137, 0.4415, 0.257, 0.245, 0.124, 258.1};  // heel to toe tip

}  // namespace detail

/// The inertial parameters of every segment that carries mass: root (de Leva's lower trunk), BP
/// (middle trunk), BT (upper trunk), BUN (head with neck; BLN carries none), and per side the upper
/// arm (S), forearm (E), hand (W), thigh (H), shank (K) and foot (A). The segments run between the
/// model's joint centres in its zero pose: the trunk from the hip centres' midpoint to the lower neck
/// joint (BLN), split in de Leva's length ratios; head, hand and foot, which end at no joint, get
/// de Leva's lengths scaled by height / 1741 mm (the head upwards from BLN, the hand downwards from
/// the wrist, the foot forwards from the model's heel marker, 0.0333 height behind the ankle, halfway
/// between the ankle and the sole). The masses add up to `body_mass_kg`.
inline std::vector<SegmentInertia> de_leva_segment_inertia(const BodyModel& model, double body_mass_kg) {
  if (!(body_mass_kg > 0) || !std::isfinite(body_mass_kg))
    throw std::invalid_argument("the body mass must be a positive number of kilograms");
  for (const char* group :
       {"BP", "BT", "BLN", "BUN", "LS", "LE", "LW", "RS", "RE", "RW", "LH", "LK", "LA", "RH", "RK", "RA"})
    if (model.frame_index(group) < 0)
      throw std::invalid_argument(std::string("segment inertia: the model has no joint group ") + group);
  const FrameTransforms zero = joint_frames(model, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(),
                                            Eigen::VectorXd::Zero(model.joint_count()));
  auto origin = [&](const char* frame) {
    return Eigen::Vector3d(zero.origins[static_cast<std::size_t>(model.frame_index(frame))]);
  };
  const double scale = model.height_mm / kDeLevaStatureMm;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  std::vector<SegmentInertia> segments;
  // A segment from `proximal` to `distal` (zero-pose model coordinates, mm) carried by `frame`;
  // `along_y`: its long axis is antero-posterior (the foot), else vertical.
  auto add = [&](const char* frame, const detail::DeLevaRow& row, const Eigen::Vector3d& proximal,
                 const Eigen::Vector3d& distal, bool along_y) {
    SegmentInertia s;
    s.segment = frame;
    s.mass_kg = row.mass * body_mass_kg;
    const int index = model.frame_index(frame);
    const Eigen::Matrix3d& rotation = zero.rotations[static_cast<std::size_t>(index)];
    const Eigen::Vector3d& frame_origin = zero.origins[static_cast<std::size_t>(index)];
    s.proximal_mm = rotation.transpose() * (proximal - frame_origin);
    s.distal_mm = rotation.transpose() * (distal - frame_origin);
    s.centre_of_mass_mm = s.proximal_mm + row.centre * (s.distal_mm - s.proximal_mm);
    const double length_m = (distal - proximal).norm() / 1000.0;
    auto moment = [&](double radius) { return s.mass_kg * radius * radius * length_m * length_m; };
    s.moments_kg_m2 =
        along_y
            ? Eigen::Vector3d(moment(row.r_sagittal), moment(row.r_longitudinal), moment(row.r_transverse))
            : Eigen::Vector3d(moment(row.r_transverse), moment(row.r_sagittal), moment(row.r_longitudinal));
    segments.push_back(s);
  };
  using namespace detail;
  const Eigen::Vector3d mid_hip = 0.5 * (origin("LHx") + origin("RHx"));
  const Eigen::Vector3d neck = origin("BLNx");
  const double trunk =
      kDeLevaLowerTrunk.length_mm + kDeLevaMiddleTrunk.length_mm + kDeLevaUpperTrunk.length_mm;
  const Eigen::Vector3d omphalion = mid_hip + kDeLevaLowerTrunk.length_mm / trunk * (neck - mid_hip);
  const Eigen::Vector3d xiphoid =
      mid_hip + (kDeLevaLowerTrunk.length_mm + kDeLevaMiddleTrunk.length_mm) / trunk * (neck - mid_hip);
  add("root", kDeLevaLowerTrunk, omphalion, mid_hip, false);
  add("BP", kDeLevaMiddleTrunk, xiphoid, omphalion, false);
  add("BT", kDeLevaUpperTrunk, neck, xiphoid, false);
  add("BUN", kDeLevaHeadNeck, neck + kDeLevaHeadNeck.length_mm * scale * up, neck, false);
  for (const char side : {'L', 'R'}) {
    auto group = [&](const char* rest) { return std::string(1, side) + rest; };
    const Eigen::Vector3d shoulder = origin(group("S").c_str()), elbow = origin(group("E").c_str()),
                          wrist = origin(group("W").c_str()), hip = origin(group("H").c_str()),
                          knee = origin(group("K").c_str()), ankle = origin(group("A").c_str());
    add(group("S").c_str(), kDeLevaUpperArm, shoulder, elbow, false);
    add(group("E").c_str(), kDeLevaForearm, elbow, wrist, false);
    add(group("W").c_str(), kDeLevaHand, wrist, wrist - kDeLevaHand.length_mm * scale * up, false);
    add(group("H").c_str(), kDeLevaThigh, hip, knee, false);
    add(group("K").c_str(), kDeLevaShank, knee, ankle, false);
    // The model's heel marker: 33.3 mm behind and 25.5 mm below the ankle per 1000 mm of height.
    const Eigen::Vector3d heel = ankle + model.height_mm / 1000.0 * Eigen::Vector3d(0, -33.3, -25.5);
    const Eigen::Vector3d foot_centre_line = heel + Eigen::Vector3d(0, 0, 12.75 * model.height_mm / 1000.0);
    add(group("A").c_str(), kDeLevaFoot, foot_centre_line,
        foot_centre_line + kDeLevaFoot.length_mm * scale * Eigen::Vector3d::UnitY(), true);
  }
  return segments;
}

}  // namespace s2kf::body
