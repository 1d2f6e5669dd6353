// Marker sets as JSON: reading, writing, finding the bundled ones and choosing one for a recording.
#include <s2kf/app/marker_set_json.hpp>

#include <s2kf/app/data_directory.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::app {

namespace {

double number(const nlohmann::json& value, const std::string& where) {
  if (!value.is_number()) throw std::invalid_argument(where + " must be a number");
  return value.get<double>();
}

std::string text(const nlohmann::json& value, const std::string& where) {
  if (!value.is_string()) throw std::invalid_argument(where + " must be a string");
  return value.get<std::string>();
}

void only_keys(const nlohmann::json& object, const std::vector<std::string>& known,
               const std::string& where) {
  for (const auto& item : object.items())
    if (std::find(known.begin(), known.end(), item.key()) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw std::invalid_argument(where + ": unknown key \"" + item.key() + "\" (known: " + list + ")");
    }
}

}  // namespace

body::MarkerSet marker_set_from_json(const nlohmann::json& document, const std::string& source) {
  if (!document.is_object()) throw std::invalid_argument(source + ": a marker set must be a JSON object");
  only_keys(
      document,
      {"name", "description", "reference_height_mm", "height_mm", "segment_scale", "joint_limits", "markers"},
      source);
  body::MarkerSet set;
  set.name = document.contains("name") ? text(document["name"], source + ": name")
                                       : std::filesystem::path(source).stem().string();
  if (document.contains("description"))
    set.description = text(document["description"], source + ": description");
  if (document.contains("reference_height_mm"))
    set.reference_height_mm = number(document["reference_height_mm"], source + ": reference_height_mm");
  if (document.contains("height_mm")) set.height_mm = number(document["height_mm"], source + ": height_mm");
  if (document.contains("segment_scale")) {
    const auto& scales = document["segment_scale"];
    if (!scales.is_object())
      throw std::invalid_argument(source + ": segment_scale must be an object {\"LS\": 1.02}");
    for (const auto& item : scales.items())
      set.segment_scale[item.key()] = number(item.value(), source + ": segment_scale." + item.key());
  }
  if (document.contains("joint_limits")) {
    const auto& limits = document["joint_limits"];
    if (!limits.is_object())
      throw std::invalid_argument(source + ": joint_limits must be an object {\"LKx\": [-2.6, 0]} (radians)");
    for (const auto& item : limits.items()) {
      const std::string where = source + ": joint_limits." + item.key();
      if (!item.value().is_array() || item.value().size() != 2)
        throw std::invalid_argument(where + " must be [lower, upper] in radians");
      set.joint_limits[item.key()] = {number(item.value()[0], where), number(item.value()[1], where)};
    }
  }
  if (!document.contains("markers") || !document["markers"].is_array())
    throw std::invalid_argument(source + ": \"markers\" must be an array of marker entries");
  int index = 0;
  for (const auto& item : document["markers"]) {
    const std::string where = source + ": marker " + std::to_string(index++);
    if (!item.is_object()) throw std::invalid_argument(where + " must be an object");
    only_keys(item, {"label", "aliases", "frame", "like", "offset", "noise_mm", "weight"}, where);
    if (!item.contains("label")) throw std::invalid_argument(where + " has no \"label\"");
    body::MarkerSetEntry entry;
    entry.label = text(item["label"], where + ": label");
    const std::string named = source + ": marker " + entry.label;
    if (item.contains("aliases")) {
      if (!item["aliases"].is_array())
        throw std::invalid_argument(named + ": aliases must be an array of strings");
      for (const auto& alias : item["aliases"]) entry.aliases.push_back(text(alias, named + ": alias"));
    }
    if (item.contains("frame")) entry.frame = text(item["frame"], named + ": frame");
    if (item.contains("like")) entry.like = text(item["like"], named + ": like");
    if (item.contains("offset")) {
      const auto& offset = item["offset"];
      if (!offset.is_array() || offset.size() != 3)
        throw std::invalid_argument(named + ": offset must be an array of 3 numbers (mm)");
      entry.offset = {number(offset[0], named + ": offset"), number(offset[1], named + ": offset"),
                      number(offset[2], named + ": offset")};
    } else if (!entry.like) {
      throw std::invalid_argument(named + " needs an \"offset\" or a \"like\" marker");
    }
    if (entry.frame.empty() && !entry.like)
      throw std::invalid_argument(named + " needs a \"frame\" (or a \"like\" marker to take it from)");
    if (item.contains("noise_mm")) entry.noise_mm = number(item["noise_mm"], named + ": noise_mm");
    if (item.contains("weight")) entry.weight = number(item["weight"], named + ": weight");
    set.entries.push_back(entry);
  }
  return set;
}

nlohmann::json marker_set_to_json(const body::MarkerSet& set) {
  nlohmann::json document = nlohmann::json::object();
  document["name"] = set.name;
  if (!set.description.empty()) document["description"] = set.description;
  document["reference_height_mm"] = set.reference_height_mm;
  if (set.height_mm) document["height_mm"] = *set.height_mm;
  if (!set.segment_scale.empty()) document["segment_scale"] = set.segment_scale;
  if (!set.joint_limits.empty()) document["joint_limits"] = set.joint_limits;
  nlohmann::json markers = nlohmann::json::array();
  for (const body::MarkerSetEntry& entry : set.entries) {
    nlohmann::json item = {{"label", entry.label}};
    if (!entry.aliases.empty()) item["aliases"] = entry.aliases;
    if (!entry.frame.empty()) item["frame"] = entry.frame;
    if (entry.like) item["like"] = *entry.like;
    item["offset"] = {entry.offset.x(), entry.offset.y(), entry.offset.z()};
    if (entry.noise_mm) item["noise_mm"] = *entry.noise_mm;
    if (entry.weight != 1.0) item["weight"] = entry.weight;
    markers.push_back(item);
  }
  document["markers"] = markers;
  return document;
}

body::MarkerSet load_marker_set(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw UserError(path.string() + ": cannot open the marker-set file");
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw UserError(path.string() + ": not valid JSON (" + e.what() + ")");
  }
  try {
    return marker_set_from_json(document, path.string());
  } catch (const std::invalid_argument& e) {
    throw UserError(e.what());
  }
}

std::filesystem::path marker_set_directory() { return data_directory() / "markersets"; }

std::vector<std::string> bundled_marker_set_names() {
  std::vector<std::string> names;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(marker_set_directory(), error))
    if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

body::MarkerSet resolve_marker_set(const std::string& name_or_file) {
  const std::filesystem::path as_path(name_or_file);
  if (as_path.extension() == ".json" || std::filesystem::exists(as_path)) {
    if (!std::filesystem::exists(as_path))
      throw UserError("the marker-set file " + name_or_file + " does not exist");
    return load_marker_set(as_path);
  }
  const std::filesystem::path bundled = marker_set_directory() / (name_or_file + ".json");
  if (std::filesystem::exists(bundled)) return load_marker_set(bundled);
  std::string known;
  for (const auto& name : bundled_marker_set_names()) known += (known.empty() ? "" : ", ") + name;
  throw UserError("unknown marker set '" + name_or_file + "' (bundled: " +
                  (known.empty() ? "none found in " + marker_set_directory().string() : known) +
                  "; or give a .json file)");
}

std::string format_fraction(double value) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(0) << 100 * value << " %";
  return s.str();
}

MarkerSetChoice choose_marker_set_for(const std::vector<std::string>& labels, const std::string& markerset,
                                      const std::string& subject) {
  if (!markerset.empty() && !subject.empty())
    throw UserError("give --markerset or --subject, not both (a subject file is a calibrated marker set)");
  MarkerSetChoice choice;
  if (!subject.empty()) {
    choice.set = resolve_marker_set(subject);
    choice.source = "subject file " + subject;
  } else if (!markerset.empty()) {
    choice.set = resolve_marker_set(markerset);
    choice.source = "given";
  } else {
    std::vector<body::MarkerSet> sets;
    for (const std::string& name : bundled_marker_set_names()) sets.push_back(resolve_marker_set(name));
    const int best = body::choose_marker_set(labels, sets);
    if (best < 0)
      throw UserError("none of the recording's labels belongs to a bundled marker set; give --markerset");
    choice.set = sets[static_cast<std::size_t>(best)];
    std::ostringstream why;
    why << "chosen automatically:";
    for (const body::MarkerSet& set : sets)
      why << " " << set.name << " " << format_fraction(body::marker_set_match(labels, set));
    choice.source = why.str();
  }
  return choice;
}

std::vector<std::string> marker_set_messages(const MarkerSetChoice& choice,
                                             const body::MarkerMapping& mapping) {
  std::vector<std::string> messages;
  messages.push_back("marker set " + choice.set.name + " (" + choice.source +
                     "): " + std::to_string(mapping.markers_used()) + " of its " +
                     std::to_string(choice.set.entries.size()) + " markers are in the recording");
  messages.insert(messages.end(), mapping.label_notes.begin(), mapping.label_notes.end());
  // Labels left out, grouped by reason: model outputs and virtual points come by the dozen.
  std::vector<std::pair<std::string, std::vector<std::string>>> by_reason;
  for (const markerset::LeftOutPoint& point : choice.left_out) {
    auto found = std::find_if(by_reason.begin(), by_reason.end(),
                              [&](const auto& group) { return group.first == point.reason; });
    if (found == by_reason.end()) found = by_reason.insert(by_reason.end(), {point.reason, {}});
    found->second.push_back(point.label);
  }
  for (const auto& [reason, labels] : by_reason) {
    std::string list;
    for (std::size_t k = 0; k < labels.size(); ++k)
      list += k < 8 ? (k == 0 ? "" : ", ") + labels[k] : k == 8 ? ", ..." : "";
    messages.push_back("left out " + std::to_string(labels.size()) + " label(s), " + reason + ": " + list);
  }
  std::vector<std::string> ignored;
  for (const std::string& label : mapping.ignored_labels)
    if (!label.empty()) ignored.push_back(label);
  if (!ignored.empty()) {
    std::string list;
    for (const std::string& label : ignored) list += (list.empty() ? "" : ", ") + label;
    messages.push_back(std::to_string(ignored.size()) + " label(s) ignored: " + list);
  }
  return messages;
}

body::MarkerSet subject_marker_set(const body::MarkerSet& original, const body::BodyModel& calibrated,
                                   const std::map<std::string, double>& segment_scale,
                                   const std::vector<double>& marker_noise_mm, const std::string& name) {
  body::MarkerSet set;
  set.name = name;
  set.description = "subject calibrated by s2kf calibrate from the marker set " + original.name;
  set.reference_height_mm = 1000.0;
  set.height_mm = calibrated.height_mm;
  for (const auto& [segment, factor] : segment_scale) {
    double combined = factor;
    if (const auto found = original.segment_scale.find(segment); found != original.segment_scale.end())
      combined *= found->second;
    set.segment_scale[segment] = combined;
  }
  for (const auto& [segment, factor] : original.segment_scale)
    if (!set.segment_scale.count(segment)) set.segment_scale[segment] = factor;
  set.joint_limits = original.joint_limits;  // the subject moves as the set said it may
  const double to_reference = 1000.0 / calibrated.height_mm;
  for (std::size_t m = 0; m < original.entries.size(); ++m) {
    body::MarkerSetEntry entry = original.entries[m];
    const body::Marker& marker = calibrated.markers[m];
    entry.like.reset();
    entry.frame = body::marker_set_frame_name(calibrated, marker.frame);
    entry.offset = marker.offset * to_reference;
    if (m < marker_noise_mm.size() && std::isfinite(marker_noise_mm[m])) entry.noise_mm = marker_noise_mm[m];
    set.entries.push_back(entry);
  }
  return set;
}

}  // namespace s2kf::app
