/// @file
/// Reading a motion file (data/motions/<name>.json) into an s2kf::sim::KeyframeMotion. The schema
/// is documented in docs/simulation.md; JSON stays out of the tracking library, so this lives in the
/// application layer.
#pragma once

#include <s2kf/core/constants.hpp>
#include <s2kf/sim/keyframe_motion.hpp>
#include <s2kf/sim/random_sweep.hpp>

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::app {

/// Joint names, order and limits the motion files are checked against.
struct JointTable {
  std::vector<std::string> names;
  Eigen::VectorXd lower, upper;  ///< rad
};

namespace detail {

inline double number(const nlohmann::json& value, const std::string& where) {
  if (!value.is_number()) throw std::invalid_argument(where + " must be a number");
  return value.get<double>();
}

inline Eigen::Vector3d triple(const nlohmann::json& value, const std::string& where) {
  if (!value.is_array() || value.size() != 3)
    throw std::invalid_argument(where + " must be an array of 3 numbers");
  return {number(value[0], where), number(value[1], where), number(value[2], where)};
}

}  // namespace detail

/// Parses a motion document. `seed` feeds procedural generators ("generator": "random_sweep").
/// Throws std::invalid_argument with a sentence that names `source` and the offending entry.
inline sim::KeyframeMotion motion_from_json(const nlohmann::json& document, const JointTable& joints,
                                            std::uint64_t seed, const std::string& source) {
  using detail::number;
  const auto fail = [&](const std::string& what) { throw std::invalid_argument(source + ": " + what); };
  if (!document.is_object()) fail("a motion file must hold a JSON object");
  const std::string name = document.value("name", std::filesystem::path(source).stem().string());

  if (document.contains("generator")) {
    const auto& generator = document["generator"];
    if (!generator.is_string() || generator.get<std::string>() != "random_sweep")
      fail("unknown generator (the only one is \"random_sweep\")");
    sim::RandomSweepOptions options;
    if (document.contains("duration"))
      options.duration_s = number(document["duration"], source + ": duration");
    if (document.contains("keyframe_interval"))
      options.keyframe_interval_s = number(document["keyframe_interval"], source + ": keyframe_interval");
    try {
      sim::KeyframeMotion motion = sim::random_sweep_motion(seed, joints.lower, joints.upper, options);
      motion.name = name;
      return motion;
    } catch (const std::invalid_argument& e) {
      fail(e.what());
    }
  }

  if (!document.contains("units") || !document["units"].is_string())
    fail("\"units\" must say \"deg\" or \"rad\" (the unit of root_rpy and the joint angles)");
  const std::string units = document["units"].get<std::string>();
  if (units != "deg" && units != "rad") fail("\"units\" must be \"deg\" or \"rad\", not \"" + units + "\"");
  const double angle_scale = units == "deg" ? 1.0 / kDegreesPerRadian : 1.0;
  if (!document.contains("keyframes") || !document["keyframes"].is_array() || document["keyframes"].empty())
    fail("\"keyframes\" must be a non-empty array");

  std::map<std::string, Eigen::Index> joint_index;
  for (std::size_t j = 0; j < joints.names.size(); ++j)
    joint_index[joints.names[j]] = static_cast<Eigen::Index>(j);

  const auto& keyframes = document["keyframes"];
  const auto count = static_cast<Eigen::Index>(keyframes.size());
  sim::KeyframeMotion motion;
  motion.name = name;
  motion.root_positions.resize(3, count);
  motion.root_rpy.resize(3, count);
  motion.joints = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(joints.names.size()), count);
  for (Eigen::Index k = 0; k < count; ++k) {
    const auto& keyframe = keyframes[static_cast<std::size_t>(k)];
    const std::string where = source + ": keyframe " + std::to_string(k);
    if (!keyframe.is_object()) throw std::invalid_argument(where + " must be an object");
    if (!keyframe.contains("time")) throw std::invalid_argument(where + " has no \"time\"");
    motion.times.push_back(number(keyframe["time"], where + " time"));
    if (!keyframe.contains("root_position")) throw std::invalid_argument(where + " has no \"root_position\"");
    motion.root_positions.col(k) = detail::triple(keyframe["root_position"], where + " root_position");
    motion.root_rpy.col(k) =
        keyframe.contains("root_rpy")
            ? Eigen::Vector3d(detail::triple(keyframe["root_rpy"], where + " root_rpy") * angle_scale)
            : Eigen::Vector3d::Zero();
    if (keyframe.contains("joints")) {
      if (!keyframe["joints"].is_object()) throw std::invalid_argument(where + " joints must be an object");
      for (const auto& [joint, value] : keyframe["joints"].items()) {
        const auto found = joint_index.find(joint);
        if (found == joint_index.end())
          throw std::invalid_argument(where + " names an unknown joint \"" + joint + "\"");
        motion.joints(found->second, k) = number(value, where + " " + joint) * angle_scale;
      }
    }
  }
  sim::validate_motion(motion, joints.lower, joints.upper, joints.names);
  return motion;
}

/// Reads and parses a motion file.
inline sim::KeyframeMotion load_motion_file(const std::filesystem::path& path, const JointTable& joints,
                                            std::uint64_t seed) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot open the motion file " + path.string());
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::invalid_argument(path.string() + " is not valid JSON: " + e.what());
  }
  return motion_from_json(document, joints, seed, path.string());
}

}  // namespace s2kf::app
