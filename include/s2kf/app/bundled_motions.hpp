/// @file
/// The bundled motions (data/motions/<name>.json) by name, and the option parsing `s2kf simulate`
/// and `s2kf evaluate --motion` share.
#pragma once

#include <s2kf/app/data_directory.hpp>
#include <s2kf/app/user_error.hpp>

#include <s2kf/sim/occlusion.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::app {

inline std::filesystem::path motions_directory() { return data_directory() / "motions"; }

inline std::vector<std::string> motion_names() {
  std::vector<std::string> names;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(motions_directory(), error))
    if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

// A name of a bundled motion or the path of a motion file.
inline std::filesystem::path resolve_motion(const std::string& motion) {
  const std::filesystem::path as_path(motion);
  if (as_path.extension() == ".json") {
    if (!std::filesystem::exists(as_path)) throw UserError("the motion file " + motion + " does not exist");
    return as_path;
  }
  const std::filesystem::path bundled = motions_directory() / (motion + ".json");
  if (std::filesystem::exists(bundled)) return bundled;
  std::string known;
  for (const auto& name : motion_names()) known += (known.empty() ? "" : ", ") + name;
  throw UserError("unknown motion '" + motion +
                  "' (known: " + (known.empty() ? "none found in " + motions_directory().string() : known) +
                  "; or give a .json file)");
}

// "a,b" -> two numbers, or a UserError naming the option.
inline std::pair<double, double> number_pair(const std::string& text, const std::string& option,
                                             const std::string& form) {
  std::istringstream in(text);
  double a = 0, b = 0;
  char comma = 0;
  if (!(in >> a >> comma >> b) || comma != ',' || !(in >> std::ws).eof() || !std::isfinite(a) ||
      !std::isfinite(b))
    throw UserError(option + " expects " + form + ", not '" + text + "'");
  return {a, b};
}

/// "--occlusion p,lambda" checked: the random occlusion process it names.
inline sim::RandomOcclusion occlusion_option(const std::string& text) {
  const auto [p, lambda] = number_pair(text, "--occlusion", "p,lambda (e.g. 0.005,100)");
  if (!(p >= 0.0 && p <= 1.0)) throw UserError("--occlusion: the probability p must lie in [0, 1]");
  if (!(lambda >= 0.0 && lambda <= sim::kMaxPoissonMean))
    throw UserError("--occlusion: the mean length lambda must lie in [0, 100000] frames");
  return {p, lambda};
}

}  // namespace s2kf::app
