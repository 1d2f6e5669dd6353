/// @file
/// Assembles the self-contained viewer page: the template with the style, an import map whose
/// entries are data: URLs of the vendored three.js modules (so nothing is fetched, and it opens
/// from file://), the metadata as JSON, the motion data as base64 and the viewer script.
#pragma once

#include "assets.hpp"
#include "base64.hpp"
#include "page_data.hpp"

#include <s2kf/body/body_model.hpp>

#include <nlohmann/json.hpp>

#include <stdexcept>
#include <string>

namespace s2kf::cli::viewer {

/// Text that may sit inside a <script> element: "</" would end the element early, and "<!--"
/// would switch the HTML parser's script states; JSON and JavaScript strings read "<\/" and "<\!--"
/// back unchanged.
inline std::string script_safe(std::string text) {
  for (std::size_t at = 0; (at = text.find("</", at)) != std::string::npos; at += 3)
    text.replace(at, 2, "<\\/");
  for (std::size_t at = 0; (at = text.find("<!--", at)) != std::string::npos; at += 5)
    text.replace(at, 4, "<\\!--");
  return text;
}

/// Text for an HTML element's content.
inline std::string html_escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '&')
      out += "&amp;";
    else if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else
      out += c;
  }
  return out;
}

/// The page's metadata (docs/viewer.md): how to read the data block, the skeleton, the joints with
/// their limits, the markers shown and the tracking summary.
inline nlohmann::json page_metadata(const PageData& data, const body::BodyModel& model,
                                    const std::string& name, double rate_hz, const nlohmann::json& summary) {
  nlohmann::json blocks = nlohmann::json::array();
  for (const DataBlock& block : data.blocks)
    blocks.push_back({{"name", block.name}, {"offset", block.offset}, {"count", block.count}});
  nlohmann::json bones = nlohmann::json::array();
  for (const auto& [parent, child] : data.skeleton.bones) bones.push_back({parent, child});
  nlohmann::json joints = nlohmann::json::array();
  for (const body::Joint& joint : model.joints)
    joints.push_back({{"name", joint.name}, {"lower", joint.lower}, {"upper", joint.upper}});
  nlohmann::json markers = nlohmann::json::array();
  for (const int m : data.markers) markers.push_back(model.markers[static_cast<std::size_t>(m)].name);
  return {{"format", "s2kf-viewer-1"},
          {"name", name},
          {"rate", rate_hz},
          {"frames_in_motion", data.frames_in_motion},
          {"frames_stored", data.frames_stored},
          {"stride", data.stride},
          {"decimated", data.stride > 1},
          {"data_limit_bytes", data.data_limit_bytes},
          {"floats_per_frame", data.floats_per_frame},
          {"checksum_fnv1a", fnv1a(data.bytes)},
          {"blocks", blocks},
          {"skeleton", {{"points", data.skeleton.names}, {"bones", bones}}},
          {"joints", joints},
          {"markers", markers},
          {"three_version", three_version()},
          {"summary", summary}};
}

/// Replaces the one occurrence of `marker` in `page`.
inline void fill(std::string& page, const std::string& marker, const std::string& text) {
  const std::size_t at = page.find(marker);
  if (at == std::string::npos) throw std::logic_error("viewer template: " + marker + " is missing");
  page.replace(at, marker.size(), text);
}

/// The page with the metadata text `meta` and the base64 data block `data`.
inline std::string assemble_page(const std::string& meta, const std::string& data, const std::string& name) {
  const auto module_url = [](const std::string& source) {
    return "data:text/javascript;base64," + base64_encode(source);
  };
  const nlohmann::json import_map = {
      {"imports",
       {{"three", module_url(three_module_source())},
        {"three/addons/OrbitControls.js", module_url(orbit_controls_source())}}}};
  std::string page = page_template();
  // Filled from the template's last marker to its first: find() then always meets the template's
  // own marker before any filled-in text (a summary may hold any string).
  fill(page, "@S2KF:SCRIPT@", script_safe(page_script()));
  fill(page, "@S2KF:DATA@", data);
  fill(page, "@S2KF:META@", script_safe(meta));
  fill(page, "@S2KF:IMPORTMAP@", import_map.dump());
  fill(page, "@S2KF:STYLE@", page_style());
  fill(page, "@S2KF:LICENCE@",
       "three.js " + std::string(three_version()) + " (inlined below), " + three_licence_text());
  fill(page, "@S2KF:TITLE@", html_escaped(name + " - s2kf viewer"));
  return page;
}

inline std::string viewer_page(const PageData& data, const body::BodyModel& model, const std::string& name,
                               double rate_hz, const nlohmann::json& summary) {
  return assemble_page(page_metadata(data, model, name, rate_hz, summary).dump(), base64_encode(data.bytes),
                       name);
}

/// The live page of `s2kf live --view`: no data; its metadata and records come as server-sent
/// events from the path "events" beside it.
inline std::string live_viewer_page(const std::string& name) {
  return assemble_page(nlohmann::json{{"format", "s2kf-viewer-1"}, {"live", true}, {"name", name}}.dump(), "",
                       name);
}

}  // namespace s2kf::cli::viewer
