/// @file
/// The definitions of <s2kf/track/tracker_options.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/track/tracker_options.hpp>

namespace s2kf::track {

S2KF_INLINE TrackerOptions paper_preset(double rate_hz) {
  TrackerOptions o;
  o.preset = "paper";
  o.samples = 301;
  o.marker_noise_mm = 10.0;
  o.position_speed_mm_per_s = 5.0 * rate_hz;       // 25 mm^2 per frame
  o.orientation_speed_rad_per_s = 1e-5 * rate_hz;  // 1e-10 rad^2 per frame
  o.joint_speed_per_s = 1e-5 * rate_hz;            // 1e-10 per frame
  o.flexion_speed_per_s = 1e-5 * rate_hz;
  o.initial_orientation_sd_rad = 1e-3;  // 1e-6
  o.initial_joint_sd = 1e-5;            // 1e-10
  o.initial_position_sd_mm = 300.0;     // replaced by the marker spread at start
  o.rigid_initialisation = false;
  o.joints_start_near_zero_pose = false;
  o.initial_iterations = 1;
  o.converging_frames = 0;
  o.converging_iterations = 1;
  o.marker_gate_probability = 0;  // the paper has no per-marker gate
  o.frozen_marker_s = 0;
  o.axial_split_sd_rad = 0;
  o.marker_dependencies = false;  // the paper's filter sees every state in every marker
  return o;
}

S2KF_INLINE TrackerOptions preset_options(const std::string& name, double rate_hz) {
  if (name == "default") return TrackerOptions{};
  if (name == "paper") return paper_preset(rate_hz);
  throw std::invalid_argument("unknown preset '" + name + "' (use default or paper)");
}

}  // namespace s2kf::track
