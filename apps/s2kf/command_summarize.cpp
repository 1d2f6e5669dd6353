// `s2kf summarize RESULTS_DIR`: one CSV row per recording from the JSON summaries a batch of
// `s2kf track` runs left in a results folder (shards of a job array included): what was tracked,
// how well, how long each stage took, and which recordings failed and why.
#include "command.hpp"

#include <s2kf/io/atomic_file.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::cli::summarize_command {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// One field of a CSV line: quoted when it holds a comma, a quote or a line break (RFC 4180).
std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

/// A JSON value as CSV text: strings as they are, numbers as the JSON has them (shortest exact
/// form), null and absent values empty.
std::string field_text(const json* value) {
  if (!value || value->is_null()) return "";
  if (value->is_string()) return value->get<std::string>();
  return value->dump();
}

/// `summary[key][subkey]...`, or null when a key is missing.
const json* find_path(const json& summary, const std::vector<const char*>& keys) {
  const json* at = &summary;
  for (const char* key : keys) {
    if (!at->is_object() || !at->contains(key)) return nullptr;
    at = &(*at)[key];
  }
  return at;
}

const std::vector<std::string> kStages{"read",     "marker_set", "height", "calibration",
                                       "tracking", "smoothing",  "writing"};

/// The columns: a name and how the row of a summary gets its value.
struct Column {
  std::string name;
  std::function<std::string(const json&)> value;
};

Column from(const std::string& name, std::initializer_list<const char*> keys) {
  return {name, [keys = std::vector<const char*>(keys)](const json& summary) {
            return field_text(find_path(summary, keys));
          }};
}

Column count_of(const std::string& name, const char* key) {
  return {name, [key](const json& summary) {
            const json* list = find_path(summary, {key});
            return list && list->is_array() ? std::to_string(list->size()) : std::string();
          }};
}

std::vector<Column> columns() {
  std::vector<Column> all{
      from("input", {"input"}),
      {"status", [](const json& s) { return s.contains("status") ? field_text(&s["status"]) : "tracked"; }},
      from("error", {"error"}),
      from("frames", {"frames"}),
      from("frames_tracked", {"frames_tracked"}),
      from("rate_hz", {"rate"}),
      from("method", {"method"}),
      from("marker_set", {"marker_set"}),
      count_of("markers_used", "markers_used"),
      count_of("labels_ignored", "labels_ignored"),
      from("height_mm", {"height_mm"}),
      from("mean_marker_distance_mm", {"mean_marker_distance_mm"}),
      from("converged_frame", {"converged_frame"}),
      from("mean_marker_distance_all_frames_mm", {"mean_marker_distance_all_frames_mm"}),
      from("calibration_frames", {"calibration", "frames"}),
      from("calibration_before_mm", {"calibration", "mean_marker_distance_before_mm"}),
      from("calibration_after_mm", {"calibration", "mean_marker_distance_after_mm"}),
      from("smoothed", {"smoothed"}),
      count_of("warnings", "warnings"),
      {"warning_messages",
       [](const json& s) {
         const json* list = find_path(s, {"warnings"});
         std::string text;
         if (list && list->is_array())
           for (const json& warning : *list) text += (text.empty() ? "" : " | ") + field_text(&warning);
         return text;
       }},
  };
  for (const std::string& stage : kStages)
    all.push_back({"seconds_" + stage, [stage](const json& s) {
                     const json* times = find_path(s, {"seconds_per_stage"});
                     return times && times->contains(stage) ? field_text(&(*times)[stage]) : std::string();
                   }});
  all.push_back({"seconds_total", [](const json& s) {
                   const json* times = find_path(s, {"seconds_per_stage"});
                   if (!times || !times->is_object()) return std::string();
                   double total = 0;
                   for (const std::string& stage : kStages)
                     if (times->contains(stage) && (*times)[stage].is_number())
                       total += (*times)[stage].get<double>();
                   return json(total).dump();
                 }});
  return all;
}

/// A tracking summary (`s2kf track`'s PREFIX.json) or a batch's failure record: an object naming
/// its input, with the tracked frames or a failure status.
bool is_track_summary(const json& value) {
  return value.is_object() && value.contains("input") &&
         (value.contains("frames_tracked") || value.value("status", std::string()) == "failed");
}

/// Every summary under `folder`, named by its path below it without ".json" (the output prefix),
/// sorted by that name. A .json file that is not JSON is listed as unreadable; JSON that is not a
/// tracking summary (a subject file, say) is left out.
std::vector<std::pair<std::string, json>> read_summaries(const fs::path& folder) {
  std::vector<std::pair<std::string, json>> summaries;
  for (const auto& entry :
       fs::recursive_directory_iterator(folder, fs::directory_options::skip_permission_denied)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".json") continue;
    const std::string name = entry.path().lexically_relative(folder).replace_extension().generic_string();
    std::ifstream in(entry.path());
    json summary;
    try {
      in >> summary;
    } catch (const json::exception&) {
      summaries.emplace_back(name, json{{"input", ""},
                                        {"status", "unreadable"},
                                        {"error", entry.path().string() + " is not valid JSON"}});
      continue;
    }
    if (is_track_summary(summary)) summaries.emplace_back(name, std::move(summary));
  }
  std::sort(summaries.begin(), summaries.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return summaries;
}

void write_table(std::ostream& out, const std::vector<std::pair<std::string, json>>& summaries) {
  const std::vector<Column> all = columns();
  out << "result";
  for (const Column& column : all) out << "," << column.name;
  out << "\n";
  for (const auto& [name, summary] : summaries) {
    out << csv_field(name);
    for (const Column& column : all) out << "," << csv_field(column.value(summary));
    out << "\n";
  }
}

void run(const std::string& folder, const std::string& out) {
  if (!fs::is_directory(folder))
    throw UserError(folder + (fs::exists(folder) ? " is not a folder" : ": no such folder") +
                    "; give the --out folder of s2kf track");
  const auto summaries = read_summaries(folder);
  if (summaries.empty())
    throw UserError(folder + " holds no tracking summaries (the .json files s2kf track writes)");
  if (out.empty()) {
    write_table(std::cout, summaries);
    return;
  }
  io::write_file_atomically(out, [&](std::ostream& file) { write_table(file, summaries); });
  const auto failed = std::count_if(summaries.begin(), summaries.end(), [](const auto& entry) {
    return entry.second.contains("status") && entry.second["status"] != "tracked";
  });
  std::cout << "Wrote " << out << ": " << summaries.size() << " recordings, " << failed
            << " of them failed.\n";
}

const RegisterCommand summarize_registration{
    "summarize", "One CSV row per tracked recording from the JSON summaries in a results folder",
    [](CLI::App& app) {
      auto folder = std::make_shared<std::string>();
      auto out = std::make_shared<std::string>();
      app.add_option("results", *folder, "the --out folder of s2kf track (searched with its subfolders)")
          ->required();
      app.add_option("--out", *out, "write the CSV to this file (default: print it)");
      app.callback([folder, out] { run(*folder, *out); });
    }};

}  // namespace
}  // namespace s2kf::cli::summarize_command
