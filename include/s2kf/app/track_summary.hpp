/// @file
/// The summary of a tracked recording (what `s2kf track` writes as PREFIX.json and the Python
/// module returns as `summary`): one builder, so the program and the module report the same keys
/// from the same numbers.
#pragma once

#include <s2kf/app/marker_set_json.hpp>

#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/tracking_metrics.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace s2kf::app {

nlohmann::json number_or_null(double value);

/// A summary number, NaN where the summary holds null.
double summary_number(const nlohmann::json& value);

/// The summary of `run` (a run of `session`): marker set and why, calibration, frames, height,
/// markers, distances (after convergence and over all frames), latency, seconds per stage and
/// warnings. `method` is "s2kf" or "baseline"; `outside` is the time the caller spent on stages
/// outside the session and the run (opening the file, finishing the outputs); the caller adds what
/// only it knows (deadline misses, the truth).
nlohmann::json track_summary(const std::string& input, const std::string& method,
                             const MarkerSetChoice& choice, const std::vector<std::string>& messages,
                             const pipeline::Session& session, const track::TrackingRun& run, bool smoothed,
                             const std::vector<std::string>& warnings, double calibration_shrink,
                             const track::StageTimes& outside = {});

/// `value` with `precision` digits after the point ("12.3").
std::string fixed_text(double value, int precision);

/// The accuracy against a simulated recording's truth, as the summary's "truth" object.
nlohmann::json truth_json(const evaluation::TruthComparison& t);

/// What `s2kf track` prints about a tracked recording, read from its summary (so the text and
/// PREFIX.json never disagree): the marker set's messages, then one paragraph of frames, markers,
/// height, calibration, convergence, latency, smoothing, pacing, the truth and the warnings.
std::string track_paragraph(const nlohmann::json& summary, const std::string& name);

}  // namespace s2kf::app
