/// @file
/// The summary of a tracked recording (what `s2kf track` writes as PREFIX.json and the Python
/// module returns as `summary`): one builder, so the program and the module report the same keys
/// from the same numbers.
#pragma once

#include "marker_set_json.hpp"

#include <s2kf/track/session.hpp>
#include <s2kf/track/tracking_metrics.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace s2kf::cli {

inline nlohmann::json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

/// A summary number, NaN where the summary holds null.
inline double summary_number(const nlohmann::json& value) {
  return value.is_number() ? value.get<double>() : std::numeric_limits<double>::quiet_NaN();
}

/// The summary of `run` (a run of `session`): marker set and why, calibration, frames, height,
/// markers, distances (after convergence and over all frames), latency, seconds per stage and
/// warnings. `method` is "s2kf" or "baseline"; `outside` is the time the caller spent on stages
/// outside the session and the run (opening the file, finishing the outputs); the caller adds what
/// only it knows (deadline misses, the truth).
inline nlohmann::json track_summary(const std::string& input, const std::string& method,
                                    const MarkerSetChoice& choice, const std::vector<std::string>& messages,
                                    const track::Session& session, const track::TrackingRun& run,
                                    bool smoothed, const std::vector<std::string>& warnings,
                                    const track::StageTimes& outside = {}) {
  // Converged where the running median over the next second falls below 1.5 times the
  // recording's median; the mean over every tracked frame is reported as well.
  const long converged =
      track::converged_frame(run.mean_marker_distance, track::frames_per_second(session.rate_hz));
  const double level = converged >= 0 ? track::mean_from(run.mean_marker_distance, converged)
                                      : std::numeric_limits<double>::quiet_NaN();
  const double overall = track::mean_from(run.mean_marker_distance, 0);
  nlohmann::json calibration = nullptr;
  if (session.calibration)
    calibration = {
        {"frames", session.calibration_frames},
        {"stretches", session.calibration_stretches},
        {"mean_marker_distance_before_mm", session.calibration->mean_marker_distance_before_mm},
        {"mean_marker_distance_after_mm", number_or_null(track::calibrated_distance_mm(session, run))},
        {"segment_scale", session.calibration->segment_scale}};
  std::vector<double> latency_ms = run.seconds;
  for (double& s : latency_ms) s *= 1000;
  // Per marker the tracker left out at least once: how often, and why (MarkerRejection).
  nlohmann::json rejected = nlohmann::json::array();
  for (std::size_t m = 0; m < run.rejected_by_innovation.size(); ++m)
    if (run.rejected_by_innovation[m] + run.rejected_as_frozen[m] > 0)
      rejected.push_back({{"marker", session.model.markers[m].name},
                          {"innovation", run.rejected_by_innovation[m]},
                          {"frozen", run.rejected_as_frozen[m]}});
  std::vector<std::string> markers_used;
  for (int m = 0; m < session.model.marker_count(); ++m)
    if (session.mapping.point_of_marker[m] >= 0) markers_used.push_back(session.model.markers[m].name);
  nlohmann::json seconds_per_stage = nlohmann::json::object();
  for (const auto& [stage, seconds] : track::stage_list(session.times + run.times + outside))
    seconds_per_stage[stage] = seconds;
  // Per segment: its markers, whether any marker informs it, how long none of its own was seen.
  nlohmann::json segments = nlohmann::json::array();
  const track::SegmentObservation& observed = run.segments;
  for (std::size_t s = 0; s < observed.segments.size(); ++s) {
    const long missing = observed.frames_without_marker[s];
    segments.push_back(
        {{"segment", observed.segments[s]},
         {"markers", observed.markers[s]},
         {"observed", static_cast<bool>(observed.informed[s])},
         {"frames_without_marker", observed.markers[s] > 0 ? nlohmann::json(missing) : nullptr},
         {"seconds_without_marker", observed.markers[s] > 0
                                        ? nlohmann::json(static_cast<double>(missing) / session.rate_hz)
                                        : nullptr}});
  }
  nlohmann::json unobserved = nullptr;
  if (!observed.unobserved_segments().empty())
    unobserved = {{"segments", observed.unobserved_segments()},
                  {"reason",
                   "no marker of the set rides on these segments or on any segment beyond them, so "
                   "nothing in the recording tells their joint angles; they are written as not "
                   "observed (NaN in the CSV and its derivatives; 0 in .mot, BVH and MMM, which hold no "
                   "missing values)"}};
  return {
      {"input", input},
      {"method", method},
      {"marker_set", choice.set.name},
      {"marker_set_source", choice.source},
      {"marker_set_messages", messages},
      {"calibration", calibration},
      {"smoothed", smoothed},
      {"preset", session.tracker.preset},
      {"motion_model", track::to_string(session.tracker.motion_model)},
      {"frames", run.frames},
      {"frames_tracked", run.frames_tracked},
      {"rate", session.rate_hz},
      {"height_mm", session.height_mm},
      {"height_source", session.height_source},
      {"markers_used", markers_used},
      {"labels_ignored", session.mapping.ignored_labels},
      {"rejected_markers", rejected},
      {"mean_marker_distance_mm", number_or_null(level)},
      {"converged_frame", converged},
      {"mean_marker_distance_all_frames_mm", number_or_null(overall)},
      {"latency_ms",
       {{"median", track::quantile(latency_ms, 0.5)}, {"p99", track::quantile(latency_ms, 0.99)}}},
      {"seconds_per_stage", seconds_per_stage},
      {"samples", method == "s2kf" ? nlohmann::json(session.tracker.samples) : nlohmann::json(nullptr)},
      {"segments", segments},
      {"unobserved", unobserved},
      {"warnings", warnings},
  };
}

}  // namespace s2kf::cli
