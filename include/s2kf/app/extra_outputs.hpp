/// @file
/// The output formats of a tracked recording (`s2kf track --formats`, `--bvh-units`, `--derivatives`):
/// the motion file paths they select, and the files written beside the motion:
/// the OpenSim model (.osim) and the recorded markers (.trc), committed with the motion files.
#pragma once

#include <s2kf/app/user_error.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/motion_stream_writer.hpp>
#include <s2kf/io/opensim_model.hpp>
#include <s2kf/io/trc_file.hpp>

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace s2kf::app {

/// What `--formats`, `--bvh-units` and `--derivatives` chose.
struct OutputSettings {
  std::vector<std::string> formats{"csv", "mot", "bvh", "osim", "trc", "mmm"};
  std::string bvh_units = "m";
  bool derivatives = false;
  double body_mass_kg = 0;  ///< --mass: the .osim's segment masses (0: from the height)

  bool wants(const std::string& format) const {
    return std::find(formats.begin(), formats.end(), format) != formats.end();
  }
};

inline const std::vector<std::string>& known_output_formats() {
  static const std::vector<std::string> formats{"csv", "mot", "bvh", "osim", "trc", "mmm"};
  return formats;
}

/// The motion files MotionStreamWriter writes for `prefix`.
inline io::MotionFilePaths motion_file_paths(const std::string& prefix, const OutputSettings& settings) {
  io::MotionFilePaths paths;
  if (settings.wants("csv")) paths.csv = prefix + ".csv";
  if (settings.wants("mot")) paths.mot = prefix + ".mot";
  if (settings.wants("bvh")) paths.bvh = prefix + ".bvh";
  if (settings.wants("mmm")) paths.mmm = prefix + "_mmm.xml";
  if (settings.derivatives) {
    paths.velocity_csv = prefix + "_vel.csv";
    paths.acceleration_csv = prefix + "_acc.csv";
  }
  return paths;
}

inline io::BvhUnits bvh_units(const OutputSettings& settings) {
  return settings.bvh_units == "cm" ? io::BvhUnits::centimetres : io::BvhUnits::metres;
}

/// Every file a track run writes for `prefix` (the summary and marker report included).
inline std::vector<std::string> output_files(const std::string& prefix, const OutputSettings& settings) {
  const io::MotionFilePaths paths = motion_file_paths(prefix, settings);
  std::vector<std::string> files;
  for (const std::string* path :
       {&paths.csv, &paths.mot, &paths.bvh, &paths.mmm, &paths.velocity_csv, &paths.acceleration_csv})
    if (!path->empty()) files.push_back(*path);
  if (settings.wants("osim")) files.push_back(prefix + ".osim");
  if (settings.wants("trc")) files.push_back(prefix + ".trc");
  files.push_back(prefix + ".json");
  files.push_back(prefix + "_markers.csv");
  files.push_back(prefix + "_segments.csv");
  return files;
}

/// Refuses, before anything is tracked, what would end in a partial or clobbered result: --truth
/// without the CSV it is compared from, two recordings that would write the same files (files of one
/// name from different folders, given one by one), an output name that is a directory, a folder
/// that cannot be written.
inline void check_outputs(const OutputSettings& settings, const std::vector<std::string>& prefixes,
                          bool with_truth) {
  namespace fs = std::filesystem;
  if (with_truth && !settings.wants("csv"))
    throw UserError("--truth compares the written CSV with the truth; add csv to --formats");
  std::map<std::string, std::string> owner;
  for (const std::string& prefix : prefixes) {
    const auto [at, inserted] = owner.emplace(fs::absolute(prefix).lexically_normal().string(), prefix);
    if (!inserted)
      throw UserError("two recordings would both write " + prefix +
                      ".*; give the folder that holds both (outputs mirror its subfolders), or track them "
                      "separately with different --out names");
    for (const std::string& file : output_files(prefix, settings))
      if (fs::is_directory(file)) throw UserError("cannot write " + file + ": it is a directory");
    // Every folder on the way must be one (or not exist yet: it is made).
    for (fs::path folder = fs::path(prefix).parent_path(); !folder.empty(); folder = folder.parent_path()) {
      if (fs::exists(folder) && !fs::is_directory(folder))
        throw UserError("cannot write into " + folder.string() + ": it is not a directory");
      if (folder == folder.parent_path()) break;  // the root
    }
  }
}

/// The model markers that see a point of the recording (those the .osim and .trc carry).
inline std::vector<std::string> used_marker_names(const body::BodyModel& model,
                                                  const body::MarkerMapping& mapping) {
  std::vector<std::string> names;
  for (int m = 0; m < model.marker_count(); ++m)
    if (mapping.point_of_marker[static_cast<std::size_t>(m)] >= 0) names.push_back(model.markers[m].name);
  return names;
}

/// Writes PREFIX.osim (the calibrated model with the used markers) and PREFIX.trc (the recording's
/// used markers, read again from `input`) as companions of `motion_files`: they appear with the
/// motion files when it finishes, and not at all when the run fails.
inline void write_model_outputs(io::MotionStreamWriter& motion_files, const OutputSettings& settings,
                                const std::string& prefix, const std::string& input,
                                const body::BodyModel& model, const body::MarkerMapping& mapping) {
  namespace fs = std::filesystem;
  const std::vector<std::string> markers = used_marker_names(model, mapping);
  const std::string name = fs::path(input).stem().string();
  if (settings.wants("osim"))
    io::write_opensim_model(motion_files.companion(prefix + ".osim"), model, name, markers,
                            settings.body_mass_kg);
  if (!settings.wants("trc")) return;
  std::ostream& trc = motion_files.companion(prefix + ".trc");
  c3d::C3dReader reader(input);
  const c3d::C3dInfo& info = reader.info();
  io::write_trc_header(trc, fs::path(prefix + ".trc").filename().string(), info.rate, info.frame_count,
                       markers);
  std::vector<int> points;
  for (int m = 0; m < model.marker_count(); ++m)
    if (mapping.point_of_marker[static_cast<std::size_t>(m)] >= 0)
      points.push_back(mapping.point_of_marker[static_cast<std::size_t>(m)]);
  c3d::Frame frame;
  Eigen::Matrix3Xd positions(3, static_cast<Eigen::Index>(points.size()));
  while (reader.read_frame(frame)) {
    for (std::size_t k = 0; k < points.size(); ++k)
      positions.col(static_cast<Eigen::Index>(k)) = frame.positions.col(points[k]);  // NaN when missing
    io::write_trc_row(trc, static_cast<long>(frame.index) + 1, static_cast<double>(frame.index) / info.rate,
                      positions);
  }
}

/// The OpenSim model of a calibrated subject (`s2kf calibrate --out SUBJECT.json` writes SUBJECT.osim),
/// written to its temporary file; the caller commits it with the subject file.
inline std::unique_ptr<io::AtomicFileWriter> prepare_subject_opensim_model(const std::string& subject_path,
                                                                           const body::BodyModel& model,
                                                                           const body::MarkerMapping& mapping,
                                                                           double body_mass_kg = 0) {
  std::filesystem::path path = subject_path;
  path.replace_extension(".osim");
  auto file = std::make_unique<io::AtomicFileWriter>(path);
  io::write_opensim_model(file->stream(), model, path.stem().string(), used_marker_names(model, mapping),
                          body_mass_kg);
  file->check();
  return file;
}

/// "Wrote PREFIX.csv, .mot, ..." for the summary paragraph.
inline std::string written_files_sentence(const std::string& prefix, const OutputSettings& settings) {
  std::ostringstream s;
  s << "Wrote " << prefix;
  const std::vector<std::string> files = output_files(prefix, settings);
  for (std::size_t i = 0; i < files.size(); ++i)
    s << (i == 0 ? "" : i + 1 == files.size() ? " and " : ", ") << files[i].substr(prefix.size());
  return s.str();
}

}  // namespace s2kf::app
