// s2kf c3d: what the C3D reader finds in a file, as a summary or as JSON (optionally with frames).
#include "command.hpp"

#include <s2kf/io/c3d_reader.hpp>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

using s2kf::cli::UserError;

struct FrameRange {
  std::int64_t begin = 0;
  std::int64_t end = 0;
};

std::int64_t parse_frame_number(const std::string& text, const std::string& range) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || text.size() > 15)
    throw UserError("--frames " + range + ": expected A:B with whole numbers 0 <= A < B, e.g. --frames 0:10");
  return std::stoll(text);
}

FrameRange parse_range(const std::string& range, std::int64_t frame_count) {
  const auto colon = range.find(':');
  if (colon == std::string::npos)
    throw UserError("--frames " + range + ": expected A:B (0-based, B exclusive), e.g. --frames 0:10");
  FrameRange r{parse_frame_number(range.substr(0, colon), range),
               parse_frame_number(range.substr(colon + 1), range)};
  if (r.begin >= r.end) throw UserError("--frames " + range + ": the first frame must come before the end");
  if (r.end > frame_count)
    throw UserError("--frames " + range + ": the file has only " + std::to_string(frame_count) +
                    " frames (valid ends are 1.." + std::to_string(frame_count) + ")");
  return r;
}

std::string full_label(const s2kf::c3d::PointLabel& label) {
  return label.subject.empty() ? label.name : label.subject + ":" + label.name;
}

void run(const std::string& file, bool json, const std::string& frames_option) {
  s2kf::c3d::C3dReader reader(file);
  const s2kf::c3d::C3dInfo& info = reader.info();
  FrameRange range{0, info.frame_count};
  const bool with_data = !frames_option.empty();
  if (with_data) range = parse_range(frames_option, info.frame_count);

  std::vector<std::int64_t> missing(static_cast<std::size_t>(info.point_count), 0);
  nlohmann::json data = nlohmann::json::array();
  reader.seek_frame(range.begin);
  s2kf::c3d::Frame frame;
  for (std::int64_t f = range.begin; f < range.end && reader.read_frame(frame); ++f) {
    nlohmann::json points = nlohmann::json::array();
    for (int p = 0; p < info.point_count; ++p) {
      if (!frame.visible(p)) ++missing[static_cast<std::size_t>(p)];
      if (!with_data) continue;
      if (frame.visible(p))
        points.push_back({frame.positions(0, p), frame.positions(1, p), frame.positions(2, p)});
      else
        points.push_back(nullptr);
    }
    if (with_data) data.push_back(std::move(points));
  }

  if (json) {
    nlohmann::json out;
    out["file"] = file;
    out["processor"] = s2kf::c3d::to_string(info.processor);
    out["format"] = s2kf::c3d::to_string(info.format);
    out["points"] = info.point_count;
    out["frames"] = range.end - range.begin;
    out["frames_in_file"] = info.frame_count;
    out["rate"] = info.rate;
    out["units"] = info.units;
    nlohmann::json labels = nlohmann::json::array();
    nlohmann::json missing_by_label = nlohmann::json::object();
    nlohmann::json model_outputs = nlohmann::json::array();
    for (std::size_t p = 0; p < info.labels.size(); ++p) {
      const std::string label = full_label(info.labels[p]);
      labels.push_back(label);
      missing_by_label[label] = missing[p];
      if (info.labels[p].model_output) model_outputs.push_back(label);
    }
    out["labels"] = labels;
    out["missing"] = missing_by_label;
    out["model_outputs"] = model_outputs;
    out["warnings"] = info.warnings;
    if (with_data) out["data"] = std::move(data);
    // Text from the file is UTF-8 (the reader decodes Latin-1); a file name that is not is replaced.
    std::cout << out.dump(1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    return;
  }

  std::printf("%s\n", file.c_str());
  std::printf("  processor %s, %s storage, %d points, %lld frames at %g Hz (first frame %d)\n",
              s2kf::c3d::to_string(info.processor), s2kf::c3d::to_string(info.format), info.point_count,
              static_cast<long long>(info.frame_count), info.rate, info.first_frame);
  std::printf("  units \"%s\" (x%g to mm), frame layout from %s, %d analog values per frame\n",
              info.units.c_str(), info.to_mm, info.layout.c_str(), info.analog.values_per_frame);
  if (with_data)
    std::printf("  frames %lld..%lld read\n", static_cast<long long>(range.begin),
                static_cast<long long>(range.end - 1));
  std::printf("  %-32s %10s\n", "point", "missing");
  for (std::size_t p = 0; p < info.labels.size(); ++p)
    std::printf("  %-32s %10lld%s\n", full_label(info.labels[p]).c_str(), static_cast<long long>(missing[p]),
                info.labels[p].model_output ? "  (model output)" : "");
  for (const std::string& warning : info.warnings) std::printf("  warning: %s\n", warning.c_str());
}

s2kf::cli::RegisterCommand reg{
    "c3d", "Show what the C3D reader finds in a file: counts, labels, missing markers, warnings",
    [](CLI::App& app) {
      auto file = std::make_shared<std::string>();
      auto json = std::make_shared<bool>(false);
      auto frames = std::make_shared<std::string>();
      app.add_option("file", *file, "C3D file")->required();
      app.add_flag("--json", *json, "print one JSON object instead of a summary");
      app.add_option("--frames", *frames, "also list the positions of frames A:B (0-based, B exclusive)");
      app.callback([file, json, frames] { run(*file, *json, *frames); });
    }};

}  // namespace
