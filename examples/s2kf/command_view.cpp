// `s2kf view RESULT_PREFIX`: the interactive 3D page (PREFIX.html) of an existing tracking result.
// The body model the motion was tracked with is rebuilt the way `s2kf track` built it (marker set,
// height and subject calibration from the summary, on the same recording), so the page shows the
// same joint centres and model markers as `s2kf track --html`.
#include "calibration_hook.hpp"
#include "command.hpp"
#include "marker_set_json.hpp"
#include "viewer/result_page.hpp"

#include <s2kf/track/tracker_options.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <iostream>
#include <memory>
#include <string>

namespace s2kf::cli::view_command {
namespace {

struct ViewSettings {
  std::string prefix;
  std::string truth;
  double max_data_mib = static_cast<double>(viewer::kDefaultDataLimitBytes) / (1 << 20);
};

const std::string kSubjectSource = "subject file ";

/// The recording's labels as `s2kf track` matches them: model outputs never match.
std::vector<std::string> matchable_labels(const c3d::C3dInfo& info) {
  std::vector<std::string> labels;
  for (const c3d::PointLabel& label : info.labels) labels.push_back(label.model_output ? std::string() : label.name);
  return labels;
}

/// The model and mapping `s2kf track` tracked the result with.
std::pair<body::BodyModel, track::MarkerMapping> tracked_model(const std::string& prefix,
                                                               const nlohmann::json& summary) {
  const std::string where = prefix + ".json";
  const std::string input = viewer::recording_path(prefix, summary);
  const std::unique_ptr<c3d::C3dReader> reader = viewer::open_recording(input);
  const c3d::C3dInfo& info = reader->info();
  std::string markerset, subject;
  const std::string source = summary.value("marker_set_source", std::string());
  if (source.rfind(kSubjectSource, 0) == 0)
    subject = source.substr(kSubjectSource.size());
  else if (source == "given")
    markerset = summary["marker_set"].is_string() ? summary["marker_set"].get<std::string>() : std::string();
  MarkerSetChoice choice;
  try {
    choice = choose_marker_set_for(matchable_labels(info), markerset, subject);
  } catch (const std::exception& e) {
    throw UserError(where + ": its marker set cannot be rebuilt (" + e.what() + ")");
  }
  if (summary["marker_set"] != choice.set.name)
    throw UserError(where + ": tracked with the marker set " + summary["marker_set"].dump() + ", but " + input +
                    " now matches " + choice.set.name);
  body::BodyModel model = choice.model;
  track::MarkerMapping mapping = choice.mapping;
  for (const c3d::PointLabel& label : info.labels)
    if (label.model_output)
      std::replace(mapping.ignored_labels.begin(), mapping.ignored_labels.end(), std::string(), label.raw);
  model = model.scaled(summary["height_mm"].get<double>());

  const nlohmann::json calibration = summary.value("calibration", nlohmann::json(nullptr));
  if (!calibration.is_null()) {
    // The calibration is deterministic: the same frames, options and model give the same subject.
    if (!calibration.is_object() || !calibration["frames"].is_number_integer())
      throw UserError(where + ": \"calibration\" has no frame count");
    track::TrackerOptions options;
    try {
      options = track::preset_options(summary.value("preset", std::string("default")), info.rate);
    } catch (const std::invalid_argument& e) {
      throw UserError(where + ": " + e.what());
    }
    if (summary["samples"].is_number_integer()) options.samples = summary["samples"].get<int>();
    apply_marker_noise(choice.set, options);
    model = calibrate_recording(*reader, model, choice, options, info.rate, track::CalibrationOptions{}.iterations,
                                calibration["frames"].get<std::int64_t>(), false)
                .model;
  }
  return {model, mapping};
}

void run_view(const ViewSettings& settings) {
  const nlohmann::json summary = viewer::load_summary(settings.prefix);
  const auto [model, mapping] = tracked_model(settings.prefix, summary);
  const auto limit = static_cast<std::size_t>(settings.max_data_mib * (1 << 20));
  const std::string page = viewer::write_result_page(settings.prefix, model, mapping, settings.truth, limit);
  std::cout << "Wrote " << page << "\n";
}

const RegisterCommand view_registration{
    "view", "Write the interactive 3D page (PREFIX.html) of a tracking result", [](CLI::App& app) {
      auto settings = std::make_shared<ViewSettings>();
      app.add_option("prefix", settings->prefix,
                     "result prefix of s2kf track (reads PREFIX.json, PREFIX.csv and the recording)")
          ->required();
      app.add_option("--truth", settings->truth, "ground-truth motion CSV: the true skeleton as a ghost");
      app.add_option("--max-data-mb", settings->max_data_mib,
                     "motion data a page may hold (MiB) before frames are decimated (default 48)")
          ->check(CLI::Range(0.01, 4096.0));
      app.callback([settings] { run_view(*settings); });
    }};

}  // namespace
}  // namespace s2kf::cli::view_command
