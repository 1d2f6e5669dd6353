/// @file
/// Writes PREFIX.html for a tracking result (`s2kf track --html`, `s2kf view`): reads PREFIX.json
/// (the summary), PREFIX.csv (the motion) and the recording the summary names, poses `model` with
/// the library's forward kinematics, and writes the page completely or not at all.
#pragma once

#include "../front_end.hpp"
#include "page_data.hpp"
#include "page_writer.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/motion_files.hpp>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

namespace s2kf::cli::viewer {

/// PREFIX.json parsed; a UserError naming the file when it is missing or not a tracking summary.
inline nlohmann::json load_summary(const std::string& prefix) {
  const std::string path = prefix + ".json";
  std::ifstream in(path);
  if (!in)
    throw UserError(path +
                    ": no such file (give the prefix of an s2kf track result, e.g. results/handstand)");
  nlohmann::json summary;
  try {
    summary = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception&) {
    throw UserError(path + ": not valid JSON (is it an s2kf track summary?)");
  }
  for (const char* key : {"input", "marker_set", "height_mm", "rate"})
    if (!summary.is_object() || !summary.contains(key))
      throw UserError(path + ": not an s2kf track summary (no \"" + std::string(key) + "\")");
  if (!summary["input"].is_string() || !summary["height_mm"].is_number() || !summary["rate"].is_number())
    throw UserError(path + ": \"input\" must be a file name and \"height_mm\", \"rate\" numbers");
  return summary;
}

/// The recording the summary names: as written (relative to the working directory), else relative
/// to the summary's own directory (a result moved together with its recording).
inline std::string recording_path(const std::string& prefix, const nlohmann::json& summary) {
  namespace fs = std::filesystem;
  const fs::path input = summary["input"].get<std::string>();
  if (fs::exists(input)) return input.string();
  const fs::path beside = fs::path(prefix).parent_path() / input;
  if (input.is_relative() && fs::exists(beside)) return beside.string();
  throw UserError(prefix + ".json names the recording " + input.string() + ", which does not exist");
}

inline std::unique_ptr<c3d::C3dReader> open_recording(const std::string& path) {
  try {
    return std::make_unique<c3d::C3dReader>(path);
  } catch (const std::exception& e) {
    throw UserError(e.what());
  }
}

inline io::MotionTable load_motion(const std::string& path, const char* what) {
  try {
    return io::load_motion_csv(path);
  } catch (const std::exception& e) {
    throw UserError(std::string(what) + e.what());
  }
}

/// Writes PREFIX.html. `model` and `mapping` are the ones the motion was tracked with; `truth_csv`
/// (may be empty) adds the true skeleton. Returns the page's path.
inline std::string write_result_page(const std::string& prefix, const body::BodyModel& model,
                                     const body::MarkerMapping& mapping, const std::string& truth_csv,
                                     std::size_t data_limit_bytes = kDefaultDataLimitBytes) {
  namespace fs = std::filesystem;
  const nlohmann::json summary = load_summary(prefix);
  const io::MotionTable motion = load_motion(prefix + ".csv", "");
  std::optional<io::MotionTable> truth;
  if (!truth_csv.empty()) truth = load_motion(truth_csv, "--truth: ");
  const std::string input = recording_path(prefix, summary);
  const std::unique_ptr<c3d::C3dReader> recording = open_recording(input);
  PageData data;
  try {
    data = build_page_data(model, mapping, motion, *recording, truth, data_limit_bytes);
  } catch (const std::exception& e) {
    throw UserError(prefix + ": " + e.what());
  }
  const std::string path = prefix + ".html";
  const std::string page =
      viewer_page(data, model, fs::path(input).stem().string(), summary["rate"].get<double>(), summary);
  io::write_file_atomically(
      path, [&](std::ostream& out) { out << page; }, std::ios::out | std::ios::binary);
  return path;
}

}  // namespace s2kf::cli::viewer
