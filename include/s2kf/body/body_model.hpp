/// @file
/// The kinematic tree of a human body as flat tables (joints in topological order, markers on the
/// frames), and the 40-joint, 50-marker MMM-style model of docs/body-model.md built from them.
#pragma once

#include <Eigen/Core>
#include <s2kf/core/compilation_mode.hpp>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace s2kf::body {

/// Number of joints of the MMM-style model, and the dimension of the tracker's state
/// [root position (3), root orientation (3), one parameter per joint (40)].
inline constexpr int kJointCount = 40;
inline constexpr int kStateDimension = 6 + kJointCount;

/// Model frame axes: x = subject's right, y = forward, z = up.
enum class Axis : int { x = 0, y = 1, z = 2 };

inline char axis_letter(Axis axis) { return "xyz"[static_cast<int>(axis)]; }

/// Whether a joint is a limb's flexion/extension: the x axis of a shoulder, elbow, hip, knee or
/// ankle of either side (LSx, REx, LKx, ...). These carry a limb's large, fast swings.
inline bool is_limb_flexion(std::string_view joint_name) {
  return joint_name.size() == 3 && joint_name[2] == 'x' && (joint_name[0] == 'L' || joint_name[0] == 'R') &&
         std::string_view("SEHKA").find(joint_name[1]) != std::string_view::npos;
}

/// One rotational degree of freedom. Frames are numbered: frame 0 is the root (pelvis), frame j + 1
/// is the frame after joint j's rotation. Joint j's frame is
///   F_{j+1} = F_{parent_frame} * Translation(translation) * Rotation(axis, q_j),
/// so a multi-DoF group is a chain of joints where only the first carries the translation and the
/// later ones hang from the previous DoF with zero translation; R = Rx * Rz * Ry falls out of it.
struct Joint {
  std::string name;      ///< e.g. "LKx"
  std::string group;     ///< the anatomical joint it belongs to, e.g. "LK"
  int parent_frame = 0;  ///< frame index, always <= this joint's index (topological order)
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  ///< mm, in the parent frame
  Axis axis = Axis::x;
  double lower = 0;  ///< rad
  double upper = 0;  ///< rad

  /// The joint this one hangs from, or -1 for the root.
  int parent_joint() const { return parent_frame - 1; }
};

/// A marker rigidly attached to a frame.
struct Marker {
  std::string name;
  int frame = 0;                                     ///< frame index (0 = root)
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< mm, in that frame
};

/// A body model is plain data: copy it, add or move markers, scale it. `height_mm` records the
/// subject height the lengths belong to, so scaled() can rescale.
struct BodyModel {
  double height_mm = 1000;
  std::vector<Joint> joints;
  std::vector<Marker> markers;

  int joint_count() const { return static_cast<int>(joints.size()); }
  int frame_count() const { return joint_count() + 1; }
  int marker_count() const { return static_cast<int>(markers.size()); }

  /// Index of the joint with this name, or -1.
  int joint_index(std::string_view name) const {
    for (int j = 0; j < joint_count(); ++j)
      if (joints[j].name == name) return j;
    return -1;
  }
  /// Index of the marker with this name, or -1.
  int marker_index(std::string_view name) const {
    for (int m = 0; m < marker_count(); ++m)
      if (markers[m].name == name) return m;
    return -1;
  }
  /// Frame index of "root", of a joint name (the frame after that DoF) or of a group name (the
  /// frame after the group's last DoF, i.e. the segment the group moves); -1 when unknown.
  int frame_index(std::string_view name) const {
    if (name == "root") return 0;
    const int joint = joint_index(name);
    if (joint >= 0) return joint + 1;
    int last = -1;
    for (int j = 0; j < joint_count(); ++j)
      if (joints[j].group == name) last = j;
    return last >= 0 ? last + 1 : -1;
  }
  /// "root" for frame 0, else the name of the joint whose rotation ends in the frame.
  std::string frame_name(int frame) const { return frame == 0 ? "root" : joints.at(frame - 1).name; }

  std::vector<std::string> joint_names() const {
    std::vector<std::string> names;
    for (const auto& joint : joints) names.push_back(joint.name);
    return names;
  }
  std::vector<std::string> marker_names() const {
    std::vector<std::string> names;
    for (const auto& marker : markers) names.push_back(marker.name);
    return names;
  }
  Eigen::VectorXd lower_limits() const {
    Eigen::VectorXd limits(joint_count());
    for (int j = 0; j < joint_count(); ++j) limits(j) = joints[j].lower;
    return limits;
  }
  Eigen::VectorXd upper_limits() const {
    Eigen::VectorXd limits(joint_count());
    for (int j = 0; j < joint_count(); ++j) limits(j) = joints[j].upper;
    return limits;
  }

  /// Adds a marker, or replaces the one with the same name.
  void set_marker(const Marker& marker) {
    const int existing = marker_index(marker.name);
    if (existing >= 0)
      markers[existing] = marker;
    else
      markers.push_back(marker);
  }

  /// The same body at another height: every length multiplied by new_height_mm / height_mm.
  BodyModel scaled(double new_height_mm) const;

  /// Throws std::invalid_argument naming the first broken rule: parents before children, frame
  /// indices in range, finite numbers, lower <= upper.
  void validate() const;
};

namespace mmm {

/// One row of the joint table of docs/body-model.md: lengths in mm for a
/// 1000 mm subject. `parent_group` is set on the first DoF of a group only ("root" or the group it
/// hangs from); later DoFs of the group (parent_group == nullptr) chain onto the previous DoF.
struct JointRow {
  const char* name;
  const char* parent_group;
  double centre_x, centre_y, centre_z;
  char axis;
  double lower, upper;
};

// clang-format off
inline constexpr JointRow kJointTable[kJointCount] = {
    {"BPx", "root", 0, 0, 40, 'x', -0.872665, 0.610865},
    {"BPz", nullptr, 0, 0, 0, 'z', -0.785398, 0.785398},
    {"BPy", nullptr, 0, 0, 0, 'y', -0.349066, 0.349066},
    {"BTx", "BP", 0, 0, 100, 'x', -0.610865, 0.471239},
    {"BTz", nullptr, 0, 0, 0, 'z', -0.628319, 0.628319},
    {"BTy", nullptr, 0, 0, 0, 'y', -0.349066, 0.349066},
    {"BLNx", "BT", 0, 0, 310, 'x', -0.785398, 0.261799},
    {"BLNz", nullptr, 0, 0, 0, 'z', -0.261799, 0.261799},
    {"BLNy", nullptr, 0, 0, 0, 'y', -0.349066, 0.349066},
    {"BUNx", "BLN", 0, 0, 340, 'x', -0.349066, 0.523599},
    {"BUNz", nullptr, 0, 0, 0, 'z', -0.349066, 0.349066},
    {"BUNy", nullptr, 0, 0, 0, 'y', -0.261799, 0.261799},
    {"LSx", "BT", -110, 0, 288, 'x', -1.22173, 3.31613},
    {"LSz", nullptr, 0, 0, 0, 'z', -1.22173, 1.0472},
    {"LSy", nullptr, 0, 0, 0, 'y', 0, 2.79253},
    {"LEx", "LS", -110, 0, 100, 'x', 0, 2.79253},
    {"LEz", nullptr, 0, 0, 0, 'z', -1.5708, 1.5708},
    {"LWx", "LE", -110, 0, -45, 'x', -0.523599, 0.349066},
    {"LWy", nullptr, 0, 0, 0, 'y', -1.22173, 1.5708},
    {"RSx", "BT", 110, 0, 288, 'x', -1.22173, 3.31613},
    {"RSz", nullptr, 0, 0, 0, 'z', -1.0472, 1.22173},
    {"RSy", nullptr, 0, 0, 0, 'y', -2.79253, 0},
    {"REx", "RS", 110, 0, 100, 'x', 0, 2.79253},
    {"REz", nullptr, 0, 0, 0, 'z', -1.5708, 1.5708},
    {"RWx", "RE", 110, 0, -45, 'x', -0.523599, 0.349066},
    {"RWy", nullptr, 0, 0, 0, 'y', -1.5708, 1.22173},
    {"LHx", "root", -52, 0, 0, 'x', -0.872665, 1.65806},
    {"LHz", nullptr, 0, 0, 0, 'z', -0.785398, 0.785398},
    {"LHy", nullptr, 0, 0, 0, 'y', -0.349066, 1.13446},
    {"LKx", "LH", -52, 0, -245, 'x', -2.26893, 0},
    {"LAx", "LK", -52, 0, -491, 'x', -0.698132, 0.523599},
    {"LAz", nullptr, 0, 0, 0, 'z', -0.523599, 0.523599},
    {"LAy", nullptr, 0, 0, 0, 'y', -0.349066, 0.349066},
    {"RHx", "root", 52, 0, 0, 'x', -0.872665, 1.65806},
    {"RHz", nullptr, 0, 0, 0, 'z', -0.785398, 0.785398},
    {"RHy", nullptr, 0, 0, 0, 'y', -1.13446, 0.349066},
    {"RKx", "RH", 52, 0, -245, 'x', -2.26893, 0},
    {"RAx", "RK", 52, 0, -491, 'x', -0.698132, 0.523599},
    {"RAz", nullptr, 0, 0, 0, 'z', -0.523599, 0.523599},
    {"RAy", nullptr, 0, 0, 0, 'y', -0.349066, 0.349066},
};
// clang-format on

/// One row of the marker table: zero-pose position (mm, 1000 mm subject) and the frame it rides on
/// ("root", a group name = after the whole group, or a joint name = after that DoF only).
struct MarkerRow {
  const char* name;
  const char* rides_on;
  double x, y, z;
};

inline constexpr int kMarkerCount = 50;

// clang-format off
inline constexpr MarkerRow kMarkerTable[kMarkerCount] = {
    {"C7", "BT", 0.0, -38.945, 309.312},
    {"CLAV", "BT", -0.205, 51.856, 278.177},
    {"STRN", "BT", -0.205, 68.433, 172.020},
    {"T10", "BT", 0.0, -62.519, 176.234},
    {"LBAK", "BT", -46.784, -51.365, 295.077},
    {"RBAK", "BT", 42.896, -67.987, 210.294},
    {"LSHO", "BT", -94.700, -1.136, 307.954},
    {"RSHO", "BT", 94.700, -1.136, 307.954},
    {"L3", "root", 0.0, -50.000, 78.222},
    {"LUPA", "LS", -136.233, 2.644, 226.530},
    {"LAEL", "LS", -140.000, 0.0, 100.000},
    {"RUPA", "RS", 136.233, 2.644, 226.530},
    {"RAEL", "RS", 140.000, 0.0, 100.000},
    {"LAOL", "LEx", -110.000, -30.000, 100.000},
    {"RAOL", "REx", 110.000, -30.000, 100.000},
    {"LFRA", "LE", -125.441, 0.930, 18.542},
    {"LWTS", "LE", -125.000, 17.500, -42.000},
    {"LWPS", "LE", -125.000, -17.500, -42.000},
    {"RWTS", "RE", 125.000, 17.500, -42.000},
    {"RWPS", "RE", 125.000, -17.500, -42.000},
    {"LHTS", "LW", -119.351, 12.663, -91.388},
    {"LHPS", "LW", -118.358, -21.035, -84.043},
    {"RHTS", "RW", 119.351, 12.663, -91.388},
    {"RHPS", "RW", 118.358, -21.035, -84.243},
    {"LFHD", "BUN", -30.750, 44.000, 440.000},
    {"RFHD", "BUN", 30.750, 43.000, 440.000},
    {"LBHD", "BUN", -30.750, -44.000, 425.000},
    {"RBHD", "BUN", 30.750, -43.000, 425.000},
    {"LASI", "root", -67.772, 43.981, 34.995},
    {"RASI", "root", 67.770, 43.981, 34.995},
    {"LPSI", "root", -37.085, -60.000, 34.995},
    {"RPSI", "root", 37.085, -60.000, 34.995},
    {"LHIP", "root", -97.150, 0.0, 0.0},
    {"RHIP", "root", 97.150, 0.0, 0.0},
    {"LTHI", "LH", -84.780, 0.0, -183.720},
    {"LKNE", "LH", -78.788, 0.0, -243.418},
    {"RTHI", "RH", 91.810, 0.0, -104.540},
    {"RKNE", "RH", 78.793, 0.0, -243.418},
    {"LTIP", "LK", -64.833, 18.920, -387.160},
    {"RTIP", "RK", 64.831, 18.510, -313.130},
    {"LANK", "LA", -74.903, 0.0, -509.253},
    {"LHEE", "LA", -51.541, -33.263, -516.500},
    {"LMT1", "LA", -25.616, 73.244, -508.206},
    {"LMT5", "LA", -80.227, 73.244, -511.008},
    {"LTOE", "LA", -36.939, 113.750, -511.680},
    {"RANK", "RA", 74.900, 0.0, -509.250},
    {"RHEE", "RA", 51.540, -33.262, -516.500},
    {"RMT1", "RA", 25.620, 73.244, -508.206},
    {"RMT5", "RA", 80.230, 73.240, -511.010},
    {"RTOE", "RA", 36.938, 113.750, -511.681},
};
// clang-format on

}  // namespace mmm

/// The 40-joint, 50-marker MMM-style model for a subject of the given height (mm): joints in the
/// state order of the spec, markers in the order of the marker table.
BodyModel mmm_body_model(double height_mm = 1750);

}  // namespace s2kf::body

#if !defined(S2KF_COMPILED)
#include <s2kf/body/body_model.hxx>
#endif
