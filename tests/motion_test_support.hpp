/// @file
/// Motions for the output-format tests: poses drawn inside the joint limits, and a model whose
/// segments are scaled unevenly (as a calibrated subject's are), so a writer that fell back on the
/// bundled table's proportions would be caught.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/io/motion_files.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "test_files.hpp"

namespace s2kf::test_support {

/// The MMM-style model at 1750 mm with the left leg 6 % longer and the right forearm 4 % shorter.
inline body::BodyModel unevenly_scaled_model() {
  body::BodyModel model = body::mmm_body_model(1750);
  for (body::Joint& joint : model.joints) {
    if (joint.name == "LKx" || joint.name == "LAx") joint.translation *= 1.06;
    if (joint.name == "RWx") joint.translation *= 0.96;
  }
  return model;
}

/// `frames` poses: root anywhere within a metre of (0, 0, 900) mm, roll/pitch/yaw up to 1.2 rad,
/// every joint uniform within its limits.
inline io::MotionTable random_poses(const body::BodyModel& model, int frames, double rate_hz, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  io::MotionTable motion;
  motion.joint_names = model.joint_names();
  motion.values.resize(frames, 6 + model.joint_count());
  for (int r = 0; r < frames; ++r) {
    motion.frame.push_back(r);
    motion.time.push_back(r / rate_hz);
    for (int c = 0; c < 3; ++c) motion.values(r, c) = 1000 * unit(random) + (c == 2 ? 900 : 0);
    for (int c = 3; c < 6; ++c) motion.values(r, c) = 1.2 * unit(random);
    for (int j = 0; j < model.joint_count(); ++j) {
      const body::Joint& joint = model.joints[j];
      motion.values(r, 6 + j) = joint.lower + (joint.upper - joint.lower) * (0.5 + 0.5 * unit(random));
    }
  }
  return motion;
}

inline std::string scratch_directory(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(s2kf::test_support::tmp_dir()) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

inline std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace s2kf::test_support
