// `s2kf view RESULT_PREFIX`: the interactive 3D page (PREFIX.html) of an existing tracking result.
// The body model the motion was tracked with is rebuilt the way `s2kf track` built it (marker set,
// height and subject calibration from the summary, on the same recording), so the page shows the
// same joint centres and model markers as `s2kf track --html`.
#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/app/sample_sets.hpp>
#include "command.hpp"
#include "viewer/result_page.hpp"

#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/pipeline/session.hpp>

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

/// The model and mapping `s2kf track` tracked the result with: the library's pipeline prepared
/// again with the summary's marker set, height, preset, sample count and calibration window. The
/// calibration is deterministic, so the same frames and options give the same subject.
std::pair<body::BodyModel, body::MarkerMapping> tracked_model(const std::string& prefix,
                                                              const nlohmann::json& summary) {
  const std::string where = prefix + ".json";
  const std::string input = viewer::recording_path(prefix, summary);
  std::unique_ptr<c3d::C3dFrameSource> source;
  try {
    source = std::make_unique<c3d::C3dFrameSource>(input);
  } catch (const std::exception& e) {
    throw UserError(e.what());
  }
  std::string markerset, subject;
  const std::string origin = summary.value("marker_set_source", std::string());
  const nlohmann::json placed = summary.value("markers_inferred", nlohmann::json::array());
  if (origin.rfind(kSubjectSource, 0) == 0)  // (with --static, the placed markers are in it too)
    subject = origin.substr(kSubjectSource.size());
  else if (placed.is_array() && !placed.empty())  // s2kf track wrote the completed set beside its outputs
    markerset = prefix + "_markerset.json";
  else if (origin == "given")
    markerset = summary["marker_set"].is_string() ? summary["marker_set"].get<std::string>() : std::string();
  else if (origin.rfind("inferred", 0) == 0)  // s2kf track wrote the inferred set beside its outputs
    markerset = prefix + "_markerset.json";
  MarkerSetChoice choice;
  try {
    choice = choose_marker_set_for(source->labels(), markerset, subject);
  } catch (const std::exception& e) {
    throw UserError(where + ": its marker set cannot be rebuilt (" + e.what() + ")");
  }
  if (summary["marker_set"] != choice.set.name)
    throw UserError(where + ": tracked with the marker set " + summary["marker_set"].dump() + ", but " +
                    input + " now matches " + choice.set.name);
  if (!summary["height_mm"].is_number()) throw UserError(where + ": \"height_mm\" is not a number");
  pipeline::SessionOptions options;
  try {
    options.tracker =
        track::preset_options(summary.value("preset", std::string("default")), source->rate_hz());
  } catch (const std::invalid_argument& e) {
    throw UserError(where + ": " + e.what());
  }
  if (summary["samples"].is_number_integer()) options.tracker.samples = summary["samples"].get<int>();
  options.height_mm = summary["height_mm"].get<double>();
  const nlohmann::json calibration = summary.value("calibration", nlohmann::json(nullptr));
  options.calibrate = !calibration.is_null();
  if (options.calibrate) {
    if (!calibration.is_object() || !calibration["frames"].is_number_integer())
      throw UserError(where + ": \"calibration\" has no frame count");
    options.calibration_frames = calibration["frames"].get<std::int64_t>();
    // Summaries written before the calibration had a sample set of its own have no count: it
    // tracked with the tracker's.
    if (calibration["samples"].is_number_integer())
      options.calibration_samples = cached_sample_set(46, calibration["samples"].get<int>());
  }
  pipeline::Session session;
  try {
    session = pipeline::prepare_session(*source, choice.set, options,
                                        cached_sample_set(46, options.tracker.samples));
  } catch (const std::invalid_argument& e) {
    throw UserError(input + ": " + e.what());
  }
  return {session.model, session.mapping};
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
