/// @file
/// Writing a motion of the body model as BVH (Biovision hierarchy), the skeleton format Blender,
/// MotionBuilder and most animation tools open.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/io/number_text.hpp>

#include <Eigen/Core>

#include <functional>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::io {

/// The length unit of a BVH file. BVH itself has no unit field; Blender's importer reads the numbers
/// as metres at its default scale 1.0, so metres is the default (centimetres are MotionBuilder's habit).
enum class BvhUnits { metres, centimetres };

/// "m" or "cm".
inline const char* bvh_units_name(BvhUnits units) { return units == BvhUnits::metres ? "m" : "cm"; }

/// Millimetres per file unit.
inline double bvh_millimetres_per_unit(BvhUnits units) { return units == BvhUnits::metres ? 1000.0 : 10.0; }

/// The BVH skeleton of a body model: its hierarchy text and how a motion row becomes a line of
/// channel values. write_bvh and MotionStreamWriter both write through it.
///
/// BVH is Y-up and these files are in metres (or centimetres, BvhUnits): a model point (x right,
/// y forward, z up, mm) becomes (x, z, -y) / 1000 (or / 10). Joints are the anatomical groups
/// (BP, BT, BLN, BUN, LS, LE, LW, RS, ..., RA) under the root "pelvis"; all channels 0 is the model's
/// zero pose, so the rest pose Blender shows is that pose. The same change of basis turns a rotation about
/// the model's x, z, y axes into one about BVH's X, Y, -Z, so every joint group keeps its x-z-y order as
/// channels "Xrotation Yrotation Zrotation" with values (qx, qz, -qy) in degrees. The root's Rz(yaw)
/// Ry(pitch) Rx(roll) becomes "Yrotation Zrotation Xrotation" = (yaw, -pitch, roll).
class BvhSkeleton {
 public:
  explicit BvhSkeleton(const body::BodyModel& model, BvhUnits units = BvhUnits::metres)
      : millimetres_per_unit_(bvh_millimetres_per_unit(units)) {
    for (const body::Joint& joint : model.joints) axes_.push_back(joint.axis);
    // One BVH joint per anatomical group (BP, BT, LS, ...): its DoFs are consecutive joints.
    std::vector<int> group_of_joint(model.joint_count(), -1);
    for (int j = 0; j < model.joint_count(); ++j) {
      const body::Joint& joint = model.joints[j];
      const int parent_joint = joint.parent_joint();
      if (parent_joint >= 0 && model.joints[parent_joint].group == joint.group) {
        group_of_joint[j] = group_of_joint[parent_joint];
        groups_[group_of_joint[j]].dofs.push_back(j);
        continue;
      }
      Group group;
      group.name = joint.group;
      group.dofs = {j};
      group.parent = parent_joint >= 0 ? group_of_joint[parent_joint] : -1;
      group.offset = joint.translation;
      group_of_joint[j] = static_cast<int>(groups_.size());
      groups_.push_back(group);
    }
    // End sites: the mean offset of the markers on a leaf group's last frame (e.g. the foot markers).
    std::vector<bool> has_child(groups_.size(), false);
    for (const Group& g : groups_)
      if (g.parent >= 0) has_child[g.parent] = true;

    std::ostringstream out;
    // 6 decimals: a micrometre in metres, well below any marker's noise.
    out << std::fixed << std::setprecision(6) << "HIERARCHY\nROOT pelvis\n{\n  OFFSET 0 0 0\n"
        << "  CHANNELS 6 Xposition Yposition Zposition Yrotation Zrotation Xrotation\n";
    const std::function<void(int, int)> write_group = [&](int g, int depth) {
      const std::string pad(2 * depth, ' ');
      const Eigen::Vector3d offset = to_bvh(groups_[g].offset);
      out << pad << "JOINT " << groups_[g].name << "\n"
          << pad << "{\n"
          << pad << "  OFFSET " << offset.x() << " " << offset.y() << " " << offset.z() << "\n"
          << pad << "  CHANNELS 3 Xrotation Yrotation Zrotation\n";
      order_.push_back(g);
      for (std::size_t c = 0; c < groups_.size(); ++c)
        if (groups_[c].parent == g) write_group(static_cast<int>(c), depth + 1);
      if (!has_child[g]) {
        const int last_frame = groups_[g].dofs.back() + 1;
        Eigen::Vector3d tip = Eigen::Vector3d::Zero();
        int count = 0;
        for (const body::Marker& marker : model.markers)
          if (marker.frame == last_frame) tip += marker.offset, ++count;
        if (count) tip /= count;
        const Eigen::Vector3d end = to_bvh(tip);
        out << pad << "  End Site\n"
            << pad << "  {\n"
            << pad << "    OFFSET " << end.x() << " " << end.y() << " " << end.z() << "\n"
            << pad << "  }\n";
      }
      out << pad << "}\n";
    };
    for (std::size_t g = 0; g < groups_.size(); ++g)
      if (groups_[g].parent < 0) write_group(static_cast<int>(g), 1);
    out << "}\n";
    hierarchy_ = out.str();
  }

  /// Joints of the model (the motion rows hold 6 + this many values).
  int joint_count() const { return static_cast<int>(axes_.size()); }

  /// "HIERARCHY" up to the closing brace of the root.
  void write_hierarchy(std::ostream& out) const { out << hierarchy_; }

  /// "MOTION", the frame count and the frame time (s). 12 decimals: importers take the rate as
  /// 1 / Frame Time, and 8 decimals made 120 Hz read as 120.00005 Hz.
  static void write_motion_header(std::ostream& out, long frames, double rate_hz) {
    out << std::fixed << "MOTION\nFrames: " << frames << "\nFrame Time: " << std::setprecision(12)
        << 1.0 / rate_hz << "\n";
  }

  /// One frame line: the root's 6 channels, then 3 per joint group (fixed, 6 decimals). `values`
  /// must be finite (BVH has no missing frames: write_bvh repeats a tracked row instead).
  void write_row(std::ostream& out, const MotionRowRef& values) const;

 private:
  struct Group {
    std::string name;
    std::vector<int> dofs;
    int parent = -1;  // group index, -1 = root
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  };

  Eigen::Vector3d to_bvh(const Eigen::Vector3d& v) const {
    return Eigen::Vector3d(v.x(), v.z(), -v.y()) / millimetres_per_unit_;
  }

  double millimetres_per_unit_;
  std::vector<body::Axis> axes_;
  std::vector<Group> groups_;
  std::vector<int> order_;  // groups in the order their channels appear
  std::string hierarchy_;
};

/// BVH of a motion (see BvhSkeleton for the axes and units). Frames without a finite pose (not
/// tracked) repeat the nearest earlier tracked pose, those before the first tracked frame the first
/// tracked pose, since BVH has no notion of a missing frame; a motion without any tracked frame is
/// written as the rest pose.
void write_bvh(std::ostream& out, const body::BodyModel& model, const MotionTable& motion, double rate_hz,
               BvhUnits units = BvhUnits::metres);

void save_bvh(const std::string& path, const body::BodyModel& model, const MotionTable& motion,
              double rate_hz, BvhUnits units = BvhUnits::metres);

}  // namespace s2kf::io

#if !defined(S2KF_COMPILED)
#include <s2kf/io/bvh.hxx>
#endif
