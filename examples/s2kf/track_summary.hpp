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
/// markers, distances (after convergence and over all frames), latency and warnings. `method` is
/// "s2kf" or "baseline"; the caller adds what only it knows (deadline misses, the truth).
inline nlohmann::json track_summary(const std::string& input, const std::string& method,
                                    const MarkerSetChoice& choice, const std::vector<std::string>& messages,
                                    const track::Session& session, const track::TrackingRun& run,
                                    bool smoothed, const std::vector<std::string>& warnings) {
  const long converged = track::converged_frame(run.mean_marker_distance);
  // The convergence rule restarts at any late frame above 1.5 times the final level, so on long
  // real recordings the mean over every tracked frame is reported as well.
  const double level = track::mean_from(run.mean_marker_distance, converged);
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
  std::vector<std::string> markers_used;
  for (int m = 0; m < session.model.marker_count(); ++m)
    if (session.mapping.point_of_marker[m] >= 0) markers_used.push_back(session.model.markers[m].name);
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
      {"mean_marker_distance_mm", number_or_null(level)},
      {"converged_frame", converged},
      {"mean_marker_distance_all_frames_mm", number_or_null(overall)},
      {"latency_ms",
       {{"median", track::quantile(latency_ms, 0.5)}, {"p99", track::quantile(latency_ms, 0.99)}}},
      {"samples", method == "s2kf" ? nlohmann::json(session.tracker.samples) : nlohmann::json(nullptr)},
      {"warnings", warnings},
  };
}

}  // namespace s2kf::cli
