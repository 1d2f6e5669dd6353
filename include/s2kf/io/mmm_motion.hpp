/// @file
/// Writing a motion in the XML motion format of the Master Motor Map framework (MMM, KIT): the
/// root pose as a "ModelPose" sensor and the joint angles as a "Kinematic" sensor, the layout of
/// the KIT Whole-Body Human Motion Database's MMM files.
#pragma once

#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/io/number_text.hpp>

#include <Eigen/Core>

#include <iomanip>
#include <ostream>
#include <string>
#include <vector>

namespace s2kf::io {

/// MMM names a joint's degree of freedom "<name>_joint" (BLNx_joint, LKx_joint, ...).
inline std::string mmm_joint_name(const std::string& joint) { return joint + "_joint"; }

/// Everything before the ModelPose sensor's measurements: the document, the motion, the reference
/// model "mmm.xml" with the Winter model processor at the subject's height (m), and the sensor's
/// opening tags.
void write_mmm_header(std::ostream& out, const std::string& motion_name, double height_mm);

/// One ModelPose measurement: root position (mm) and roll, pitch, yaw (rad, R = Rz Ry Rx).
void write_mmm_model_pose(std::ostream& out, double time_s, const MotionRowRef& values);

/// Closes the ModelPose sensor and opens the Kinematic sensor with its joint list.
void write_mmm_kinematic_header(std::ostream& out, const std::vector<std::string>& joint_names);

/// One Kinematic measurement: the joint angles (rad) in the configuration's order.
void write_mmm_joint_position(std::ostream& out, double time_s, const MotionRowRef& values);

inline void write_mmm_footer(std::ostream& out) {
  out << "        </Data>\n      </Sensor>\n    </Sensors>\n  </Motion>\n</MMM>\n";
}

/// The whole MMM document of a motion; untracked frames are left out (MMM has no missing values).
void write_mmm_motion(std::ostream& out, const MotionTable& motion, const std::string& motion_name,
                      double height_mm);

void save_mmm_motion(const std::string& path, const MotionTable& motion, const std::string& motion_name,
                     double height_mm);

}  // namespace s2kf::io

#if !defined(S2KF_COMPILED)
#include <s2kf/io/mmm_motion.hxx>
#endif
