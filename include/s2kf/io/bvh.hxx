/// @file
/// The definitions of <s2kf/io/bvh.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/io/bvh.hpp>

namespace s2kf::io {

S2KF_INLINE void BvhSkeleton::write_row(std::ostream& out, const MotionRowRef& values) const {
  const double degrees = kDegreesPerRadian;
  const Eigen::Vector3d position = to_bvh(values.head<3>());
  out << std::fixed << std::setprecision(6);
  const double root[6] = {position.x(),        position.y(),         position.z(),
                          values(5) * degrees, -values(4) * degrees, values(3) * degrees};
  for (int k = 0; k < 6; ++k) {
    if (k) out << " ";
    write_fixed(out, root[k], 6);
  }
  for (int g : order_) {
    double channel[3] = {0, 0, 0};  // X, Y, Z
    for (int j : groups_[g].dofs) {
      const double q = angle_or_zero(values(6 + j)) * degrees;
      switch (axes_[j]) {
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
    for (const double value : channel) {
      out << " ";
      write_fixed(out, value, 6);
    }
  }
  out << "\n";
}

S2KF_INLINE void write_bvh(std::ostream& out, const body::BodyModel& model, const MotionTable& motion,
                           double rate_hz, BvhUnits units) {
  motion.check();
  if (static_cast<int>(motion.joint_names.size()) != model.joint_count())
    throw std::invalid_argument("write_bvh: the motion's joints do not match the body model");
  const BvhSkeleton skeleton(model, units);
  skeleton.write_hierarchy(out);
  BvhSkeleton::write_motion_header(out, static_cast<long>(motion.frames()), rate_hz);
  Eigen::Index first_tracked = -1;
  for (Eigen::Index r = 0; r < motion.frames() && first_tracked < 0; ++r)
    if (is_tracked_row(motion.values.row(r).transpose())) first_tracked = r;
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(motion.values.cols());
  Eigen::Index source = first_tracked;
  for (Eigen::Index r = 0; r < motion.frames(); ++r) {
    if (is_tracked_row(motion.values.row(r).transpose())) source = r;
    if (source >= 0)
      skeleton.write_row(out, motion.values.row(source).transpose());
    else
      skeleton.write_row(out, rest);
  }
}

S2KF_INLINE void save_bvh(const std::string& path, const body::BodyModel& model, const MotionTable& motion,
                          double rate_hz, BvhUnits units) {
  write_file_atomically(path, [&](std::ostream& out) { write_bvh(out, model, motion, rate_hz, units); });
}

}  // namespace s2kf::io
