/// @file
/// Writing a motion of the body model as BVH (Biovision hierarchy), the skeleton format Blender,
/// MotionBuilder and most animation tools open.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/motion_files.hpp>

#include <Eigen/Core>

#include <functional>
#include <iomanip>
#include <ostream>
#include <string>
#include <vector>

namespace s2kf::io {

/// BVH is Y-up and these files are in centimetres: a model point (x right, y forward, z up, mm)
/// becomes (x, z, -y) / 10. The same change of basis turns a rotation about the model's x, z, y axes
/// into one about BVH's X, Y, -Z, so every joint group keeps its x-z-y order as channels
/// "Xrotation Yrotation Zrotation" with values (qx, qz, -qy) in degrees. The root's
/// Rz(yaw) Ry(pitch) Rx(roll) becomes "Yrotation Zrotation Xrotation" = (yaw, -pitch, roll).
/// Frames without a finite pose (not tracked) repeat the nearest tracked pose, since BVH has no
/// notion of a missing frame.
inline void write_bvh(std::ostream& out, const body::BodyModel& model, const MotionTable& motion,
                      double rate_hz) {
  motion.check();
  if (static_cast<int>(motion.joint_names.size()) != model.joint_count())
    throw std::invalid_argument("write_bvh: the motion's joints do not match the body model");
  auto to_bvh = [](const Eigen::Vector3d& v) -> Eigen::Vector3d {
    return Eigen::Vector3d(v.x(), v.z(), -v.y()) / 10.0;
  };
  const double degrees = 180.0 / 3.14159265358979323846;

  // One BVH joint per anatomical group (BP, BT, LS, ...): its DoFs are consecutive joints.
  struct Group {
    std::string name;
    std::vector<int> dofs;
    int parent = -1;  // group index, -1 = root
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  };
  std::vector<Group> groups;
  std::vector<int> group_of_joint(model.joint_count(), -1);
  for (int j = 0; j < model.joint_count(); ++j) {
    const body::Joint& joint = model.joints[j];
    const int parent_joint = joint.parent_joint();
    if (parent_joint >= 0 && model.joints[parent_joint].group == joint.group) {
      group_of_joint[j] = group_of_joint[parent_joint];
      groups[group_of_joint[j]].dofs.push_back(j);
      continue;
    }
    Group group;
    group.name = joint.group;
    group.dofs = {j};
    group.parent = parent_joint >= 0 ? group_of_joint[parent_joint] : -1;
    group.offset = joint.translation;
    group_of_joint[j] = static_cast<int>(groups.size());
    groups.push_back(group);
  }
  // End sites: the mean offset of the markers on a leaf group's last frame (e.g. the foot markers).
  std::vector<bool> has_child(groups.size(), false);
  for (const Group& g : groups)
    if (g.parent >= 0) has_child[g.parent] = true;

  out << std::fixed << std::setprecision(4) << "HIERARCHY\nROOT pelvis\n{\n  OFFSET 0 0 0\n"
      << "  CHANNELS 6 Xposition Yposition Zposition Yrotation Zrotation Xrotation\n";
  std::vector<int> order;  // groups in the order their channels appear
  const std::function<void(int, int)> write_group = [&](int g, int depth) {
    const std::string pad(2 * depth, ' ');
    const Eigen::Vector3d offset = to_bvh(groups[g].offset);
    out << pad << "JOINT " << groups[g].name << "\n"
        << pad << "{\n"
        << pad << "  OFFSET " << offset.x() << " " << offset.y() << " " << offset.z() << "\n"
        << pad << "  CHANNELS 3 Xrotation Yrotation Zrotation\n";
    order.push_back(g);
    for (std::size_t c = 0; c < groups.size(); ++c)
      if (groups[c].parent == g) write_group(static_cast<int>(c), depth + 1);
    if (!has_child[g]) {
      const int last_frame = groups[g].dofs.back() + 1;
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
  for (std::size_t g = 0; g < groups.size(); ++g)
    if (groups[g].parent < 0) write_group(static_cast<int>(g), 1);
  out << "}\nMOTION\nFrames: " << motion.frames() << "\nFrame Time: " << std::setprecision(8) << 1.0 / rate_hz
      << "\n"
      << std::setprecision(4);

  // Rows to print: each untracked row takes the nearest tracked one (earlier ones the first).
  std::vector<Eigen::Index> source(motion.frames(), -1);
  Eigen::Index last = -1;
  for (Eigen::Index r = 0; r < motion.frames(); ++r) {
    if (motion.values.row(r).allFinite()) last = r;
    source[r] = last;
  }
  Eigen::Index first_tracked = -1;
  for (Eigen::Index r = 0; r < motion.frames() && first_tracked < 0; ++r)
    if (motion.values.row(r).allFinite()) first_tracked = r;
  for (Eigen::Index r = 0; r < motion.frames(); ++r) {
    const Eigen::Index s = source[r] >= 0 ? source[r] : first_tracked;
    Eigen::VectorXd v = Eigen::VectorXd::Zero(motion.values.cols());
    if (s >= 0) v = motion.values.row(s).transpose();
    const Eigen::Vector3d position = to_bvh(v.head<3>());
    out << position.x() << " " << position.y() << " " << position.z() << " " << v(5) * degrees << " "
        << -v(4) * degrees << " " << v(3) * degrees;
    for (int g : order) {
      double channel[3] = {0, 0, 0};  // X, Y, Z
      for (int j : groups[g].dofs) {
        const double q = v(6 + j) * degrees;
        switch (model.joints[j].axis) {
          case body::Axis::x:
            channel[0] = q;
            break;
          case body::Axis::z:
            channel[1] = q;
            break;
          case body::Axis::y:
            channel[2] = -q;
            break;
        }
      }
      out << " " << channel[0] << " " << channel[1] << " " << channel[2];
    }
    out << "\n";
  }
}

inline void save_bvh(const std::string& path, const body::BodyModel& model, const MotionTable& motion,
                     double rate_hz) {
  write_file_atomically(path, [&](std::ostream& out) { write_bvh(out, model, motion, rate_hz); });
}

}  // namespace s2kf::io
