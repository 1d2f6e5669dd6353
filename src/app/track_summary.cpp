// The summary of one tracked recording: its JSON object and the paragraph the program prints.
#include <s2kf/app/track_summary.hpp>

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace s2kf::app {

nlohmann::json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

double summary_number(const nlohmann::json& value) {
  return value.is_number() ? value.get<double>() : std::numeric_limits<double>::quiet_NaN();
}

nlohmann::json track_summary(const std::string& input, const std::string& method,
                             const MarkerSetChoice& choice, const std::vector<std::string>& messages,
                             const pipeline::Session& session, const track::TrackingRun& run, bool smoothed,
                             const std::vector<std::string>& warnings, double calibration_shrink,
                             const track::StageTimes& outside) {
  // Converged where the running median over the next second falls below 1.5 times the
  // recording's median; the mean over every tracked frame is reported as well.
  const track::DistanceLevel distance = track::distance_level(run, session.rate_hz);
  // The markers the set did not name, placed by their motion, and the labels left out.
  nlohmann::json inferred = nlohmann::json::array(), left_out = nlohmann::json::array();
  for (const markerset::CompletedMarker& m : choice.inferred)
    inferred.push_back({{"label", m.label},
                        {"segment", m.segment},
                        {"frame", m.frame},
                        {"spread_mm", m.spread_mm},
                        {"confidence", m.confidence}});
  for (const markerset::LeftOutPoint& p : choice.left_out)
    left_out.push_back({{"label", p.label}, {"reason", p.reason}});
  nlohmann::json calibration = nullptr;
  if (session.calibration)
    calibration = {
        {"frames", session.calibration_frames},
        {"samples", session.calibration_sample_count},
        {"stretches", session.calibration_stretches},
        {"mean_marker_distance_before_mm", session.calibration->mean_marker_distance_before_mm},
        {"mean_marker_distance_after_mm", number_or_null(pipeline::calibrated_distance_mm(session, run))},
        {"segment_scale", session.calibration->segment_scale},
        {"bundle_frames", session.calibration->passes.front().frames_used},
        {"bundle_iterations", session.calibration->passes.front().bundle_iterations},
        {"weak_direction_shrink", calibration_shrink},
        {"marker_noise_mm", [&] {
           // Each marker's noise where it differs from the common one (noise from the calibration).
           nlohmann::json noise = nlohmann::json::object();
           const std::vector<double>& sd = session.tracker.marker_noise_mm_per_marker;
           for (std::size_t m = 0; m < sd.size() && m < session.model.markers.size(); ++m)
             if (std::isfinite(sd[m])) noise[session.model.markers[m].name] = sd[m];
           return noise;
         }()}};
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
      {"markers_inferred", inferred},
      {"labels_left_out", left_out},
      {"calibration", calibration},
      {"smoothed", smoothed},
      {"preset", session.tracker.preset},
      {"motion_model", track::to_string(session.tracker.motion_model)},
      {"gain", track::gain_name(session.tracker)},
      {"frames", run.frames},
      {"frames_tracked", run.frames_tracked},
      {"rate", session.rate_hz},
      {"height_mm", session.height_mm},
      {"height_source", session.height_source},
      {"markers_used", markers_used},
      {"labels_ignored", session.mapping.ignored_labels},
      {"rejected_markers", rejected},
      {"mean_marker_distance_mm", number_or_null(distance.level_mm)},
      {"converged_frame", distance.converged_frame},
      {"mean_marker_distance_all_frames_mm", number_or_null(distance.overall_mm)},
      {"latency_ms",
       {{"median", 1000 * track::seconds_quantile(run, 0.5)},
        {"p99", 1000 * track::seconds_quantile(run, 0.99)}}},
      {"seconds_per_stage", seconds_per_stage},
      {"samples", method == "s2kf" ? nlohmann::json(session.tracker.samples) : nlohmann::json(nullptr)},
      {"segments", segments},
      {"unobserved", unobserved},
      {"warnings", warnings},
  };
}

std::string fixed_text(double value, int precision) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << value;
  return s.str();
}

nlohmann::json truth_json(const evaluation::TruthComparison& t) {
  nlohmann::json segments = nlohmann::json::object();
  for (const auto& [name, rms] : t.segment_rms_deg) segments[name] = number_or_null(rms);
  return {{"frames_compared", t.frames},
          {"segment_orientation_rms_deg", t.segment_orientation_rms_deg},
          {"limb_flexion_rms_deg", t.limb_flexion_rms_deg},
          {"all_joint_rms_deg", t.all_joint_rms_deg},
          {"worst_joint", t.worst_joint},
          {"worst_joint_rms_deg", t.worst_joint_rms_deg},
          {"root_position_rms_mm", t.root_position_rms_mm},
          {"root_orientation_rms_deg", t.root_orientation_rms_deg},
          {"joint_limit_violations", t.joint_limit_violations},
          {"segment_rms_deg", segments}};
}

std::string track_paragraph(const nlohmann::json& summary, const std::string& name) {
  const auto millimetres = [](const nlohmann::json& value) {
    return value.is_number() && std::isfinite(value.get<double>()) ? fixed_text(value.get<double>(), 1)
                                                                   : std::string("n/a");
  };
  std::ostringstream paragraph;
  for (const auto& message : summary["marker_set_messages"]) paragraph << message.get<std::string>() << "\n";
  paragraph << name << ": tracked " << summary["frames_tracked"].get<long>() << " of "
            << summary["frames"].get<long>() << " frames at " << fixed_text(summary["rate"].get<double>(), 0)
            << " Hz with " << summary["markers_used"].size() << " markers ("
            << summary["labels_ignored"].size() << " labels ignored), body height "
            << fixed_text(summary["height_mm"].get<double>(), 0) << " mm ("
            << summary["height_source"].get<std::string>() << "), marker set "
            << summary["marker_set"].get<std::string>();
  const nlohmann::json& calibration = summary["calibration"];
  if (!calibration.is_null())
    paragraph << ", calibrated on " << calibration["frames"].get<long>() << " frames ("
              << millimetres(calibration["mean_marker_distance_before_mm"]) << " -> "
              << millimetres(calibration["mean_marker_distance_after_mm"]) << " mm)";
  const double level = summary_number(summary["mean_marker_distance_mm"]);
  const double overall = summary_number(summary["mean_marker_distance_all_frames_mm"]);
  if (std::isfinite(level))
    paragraph << ". Converged at frame " << summary["converged_frame"].get<long>()
              << "; mean marker distance after that " << fixed_text(level, 1) << " mm ("
              << fixed_text(overall, 1) << " mm over all tracked frames)";
  else
    paragraph << ". The marker distance never settled (its median over a second stayed above 1.5 times its "
                 "median over the recording); mean "
              << fixed_text(overall, 1) << " mm over all tracked frames";
  paragraph << ". Latency per frame: median " << fixed_text(summary["latency_ms"]["median"].get<double>(), 3)
            << " ms, p99 " << fixed_text(summary["latency_ms"]["p99"].get<double>(), 3) << " ms";
  if (!summary["samples"].is_null()) paragraph << " (" << summary["samples"].get<int>() << " samples)";
  paragraph << ".";
  if (summary["smoothed"].get<bool>())
    paragraph << " Motion smoothed (RTS); marker distances are the filter's.";
  if (summary.contains("deadline_misses"))
    paragraph << " Real-time pacing: " << summary["deadline_misses"].get<long>() << " deadline misses.";
  if (summary.contains("truth")) {
    const nlohmann::json& truth = summary["truth"];
    paragraph << " Against the truth (frames " << truth["warmup_frames"].get<long>() << " on): all-joint RMS "
              << fixed_text(truth["all_joint_rms_deg"].get<double>(), 2) << " deg, segment orientation "
              << fixed_text(truth["segment_orientation_rms_deg"].get<double>(), 2) << " deg, limb flexion "
              << fixed_text(truth["limb_flexion_rms_deg"].get<double>(), 2) << " deg, root position "
              << fixed_text(truth["root_position_rms_mm"].get<double>(), 1) << " mm.";
  }
  return paragraph.str();
}

}  // namespace s2kf::app
