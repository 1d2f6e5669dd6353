// `s2kf evaluate` (evaluate_run.hpp): the paper's evaluation (section 5) reproduced and extended:
// the S2KF and the per-frame gradient baseline on one recording, the occlusion Monte Carlo, the
// sample-count sweep, accuracy against ground truth; CSV series, gnuplot figures and a summary.json.
#include "evaluate_run.hpp"
#include "evaluation_inputs.hpp"

#include <s2kf/app/bundled_motions.hpp>
#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/app/motion_json.hpp>
#include <s2kf/app/sample_sets.hpp>
#include <s2kf/app/track_summary.hpp>
#include "evaluation_files.hpp"
#include "front_end.hpp"

#include <s2kf/evaluation/evaluation.hpp>
#include <s2kf/evaluation/hidden_time_error.hpp>
#include <s2kf/evaluation/identifiable_subject_reference.hpp>
#include <s2kf/evaluation/true_subject_reference.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>

namespace s2kf::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// The sample count the comparison and the Monte Carlo use: the tracker's default when listed.
constexpr int kDefaultSamples = 301;
/// 2 N for the 46-dimensional state: the smallest symmetric sample set.
constexpr int kMinSamples = 92;

std::vector<int> parse_samples(const std::string& text) {
  std::vector<int> counts;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    char* end = nullptr;
    const long value = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || value < kMinSamples || value > 100001)
      throw UserError("--samples takes a comma-separated list of sample counts from " +
                      std::to_string(kMinSamples) + " to 100001, e.g. 93,301,461; '" + item + "' is not one");
    if (std::find(counts.begin(), counts.end(), static_cast<int>(value)) == counts.end())
      counts.push_back(static_cast<int>(value));
  }
  if (counts.empty() || text.back() == ',')
    throw UserError("--samples takes a comma-separated list of sample counts, e.g. 93,301,461");
  return counts;
}

std::string machine_name() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
    }
  return "unknown";
}

json hidden_time_json(const evaluation::HiddenTimeError& e) {
  const auto bins = [](const std::vector<evaluation::HiddenTimeBin>& b) {
    json out = json::array();
    for (const evaluation::HiddenTimeBin& bin : b)
      out.push_back({{"hidden_from_s", bin.lower_s},
                     {"hidden_to_s", std::isfinite(bin.upper_s) ? json(bin.upper_s) : json(nullptr)},
                     {"frames", bin.frames},
                     {"rms_deg", number_or_null(bin.rms_deg)}});
    return out;
  };
  json segments = json::object();
  for (const evaluation::SegmentHiddenTimeError& s : e.segments)
    segments[s.segment] = {{"markers", s.markers}, {"bins", bins(s.bins)}};
  return {{"all_segments", bins(e.all)}, {"segments", segments}};
}

json result_json(const evaluation::MethodResult& r) {
  json j = {{"method", pipeline::to_string(r.method)},
            {"samples", r.samples ? json(r.samples) : json(nullptr)},
            {"converged_frame", r.converged_frame},
            {"mean_marker_distance_mm", number_or_null(r.level_mm)},
            {"worst_frame_after_convergence", r.worst_frame},
            {"worst_marker_distance_after_convergence_mm", number_or_null(r.worst_mm)},
            {"worst_marker_distance_mm", number_or_null(r.worst_all_frames_mm)},
            {"latency_ms",
             {{"median", number_or_null(r.median_ms)},
              {"p99", number_or_null(r.p99_ms)},
              {"max", number_or_null(r.max_ms)}}}};
  if (r.truth) j["truth"] = truth_json(*r.truth);
  return j;
}

}  // namespace

void run_evaluate(const EvaluateSettings& settings) {
  const bool progress = !settings.quiet;
  const bool terminal = progress && isatty(STDERR_FILENO);
  const auto started = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  };
  auto say = [&](const std::string& text) {
    if (progress)
      std::cerr << "evaluate [" << std::fixed << std::setprecision(0) << elapsed() << " s] " << text << "\n";
  };

  // Inputs: a recording (with its truth when there is one), or a motion simulated here.
  std::string recording_path = settings.recording, truth_path = settings.truth;
  std::optional<Simulated> simulated;
  if (!settings.motion.empty()) {
    simulated = simulate_for_evaluation(settings);
    recording_path = "simulated " + settings.motion + " (subject seed " +
                     std::to_string(settings.subject_seed) +
                     (settings.occlusion.empty() ? "" : ", occlusion " + settings.occlusion) + ")";
  } else {
    if (!settings.occlusion.empty()) throw UserError("--occlusion applies to a simulated --motion only");
    if (recording_path.empty()) {
      recording_path = std::string(S2KF_DATA_DIR) + "/handstand.c3d";
      if (truth_path.empty()) truth_path = std::string(S2KF_DATA_DIR) + "/handstand_truth.csv";
    } else if (truth_path.empty()) {
      const fs::path beside =
          fs::path(recording_path).parent_path() / (fs::path(recording_path).stem().string() + "_truth.csv");
      if (fs::exists(beside)) truth_path = beside.string();
    }
    if (!fs::exists(recording_path)) throw UserError(recording_path + ": no such file");
    if (!truth_path.empty() && !fs::exists(truth_path)) throw UserError(truth_path + ": no such file");
  }
  const std::vector<int> sample_counts = parse_samples(settings.samples);
  const int main_samples =
      std::find(sample_counts.begin(), sample_counts.end(), kDefaultSamples) != sample_counts.end()
          ? kDefaultSamples
          : sample_counts.front();

  MarkerSequence complete;
  if (simulated) {
    complete = simulated->recording;
  } else {
    try {
      complete = c3d::read_c3d(recording_path);
    } catch (const std::exception& e) {
      throw UserError(e.what());
    }
  }
  const Eigen::Index recorded_frames = complete.frame_count();
  if (settings.frames > 0 && settings.frames < complete.frame_count())
    complete = complete.frames(0, settings.frames);
  // Prepared exactly as `s2kf track` prepares a recording: the best-matching marker set, the
  // estimated height, and the subject calibration unless --no-calibrate.
  pipeline::Session setup;
  try {
    SequenceFrameSource source(complete);
    const MarkerSetChoice choice = choose_marker_set_for(complete.labels, "", "");
    pipeline::SessionOptions options;
    options.calibrate = settings.calibrate;
    options.noise_from_calibration = settings.noise_from_calibration;
    options.tracker.motion_model = track::motion_model_from_name(settings.motion_model);
    track::set_gain_from_name(options.tracker, settings.gain);
    setup = pipeline::prepare_session(source, choice.set, options,
                                      cached_sample_set(46, options.tracker.samples));
  } catch (const std::invalid_argument& e) {
    throw UserError(recording_path + ": " + e.what());
  }
  std::optional<io::MotionTable> truth;
  if (simulated) {
    truth = sim::truth_motion(simulated->recording, setup.model.joint_names());
    truth_path = "simulated";
  } else if (!truth_path.empty()) {
    try {
      truth = io::load_motion_csv(truth_path);
      evaluation::check_truth(*truth, setup, recorded_frames);
    } catch (const std::exception& e) {
      throw UserError(truth_path + ": " + e.what() + " (" + recording_path + ")");
    }
    truth = evaluation::first_rows(*truth, settings.frames);
  }
  const io::MotionTable* truth_ptr = truth ? &*truth : nullptr;
  const std::size_t frames = static_cast<std::size_t>(complete.frame_count());
  int hidden_in_input = 0;
  for (int p : setup.mapping.point_of_marker)
    if (p >= 0) hidden_in_input += static_cast<int>((!complete.visible.row(p)).count());
  say(recording_path + ": " + std::to_string(frames) + " frames at " + cell(setup.rate_hz) + " Hz, " +
      std::to_string(setup.mapping.markers_used()) + " markers, body height " +
      cell(std::round(setup.height_mm)) + " mm" + (truth ? ", truth " + truth_path : ", no truth"));

  // The sample-count sweep; the run at the default L is the S2KF of the comparison.
  std::vector<evaluation::MethodResult> sweep;
  for (int samples : sample_counts) {
    sweep.push_back(evaluation::evaluate_method(setup, complete, pipeline::Method::s2kf, samples, truth_ptr,
                                                settings.warmup));
    say("S2KF with L = " + std::to_string(samples) + ": " + cell(sweep.back().level_mm) + " mm, median " +
        cell(sweep.back().median_ms) + " ms per frame");
  }
  const evaluation::MethodResult& s2kf = sweep[static_cast<std::size_t>(
      std::find(sample_counts.begin(), sample_counts.end(), main_samples) - sample_counts.begin())];
  const evaluation::MethodResult baseline =
      evaluation::evaluate_method(setup, complete, pipeline::Method::baseline, 0, truth_ptr, settings.warmup);
  say("baseline: " + cell(baseline.level_mm) + " mm, median " + cell(baseline.median_ms) + " ms per frame");

  // The reachable reference (simulated input only) and the smoothed S2KF, against the truth.
  std::optional<evaluation::TruthComparison> reference, smoothed, model_fit;
  json true_subject_tracking = nullptr;
  json constant_placement = nullptr, at_true_poses = nullptr;
  json identifiable = json::array();
  // How the segments' error grows with the time their markers have been hidden (the input's own
  // occlusion; everything lands in the first bin without it).
  json error_by_time_hidden = nullptr;
  const auto hidden_time = [&](const io::MotionTable& motion) {
    return hidden_time_json(evaluation::hidden_time_error(setup.model, motion, *truth, complete.visible,
                                                          setup.mapping, setup.rate_hz, settings.warmup));
  };
  if (truth) error_by_time_hidden = {{"s2kf", hidden_time(s2kf.run.motion)}};
  // The RTS-smoothed motion of a session over the whole recording.
  const auto smoothed_motion = [&](const pipeline::Session& session) {
    SequenceFrameSource source(complete);
    pipeline::RunOptions run_options;
    run_options.smooth = true;
    return pipeline::run_session(session, source, cached_sample_set(46, session.tracker.samples), run_options)
        .motion;
  };
  if (simulated) {
    reference = evaluation::compare_with_truth(
        setup.model, evaluation::true_subject_fit(simulated->subject, simulated->recording), *truth,
        settings.warmup);
    say("true-subject fit: segment orientation RMS " + cell(reference->segment_orientation_rms_deg) + " deg");
    identifiable = identifiable_references(setup, *simulated, *truth, settings.warmup);
    constant_placement = constant_placement_reference(setup, *simulated, *truth, settings.warmup);
    say("best-constant-placement fit: segment orientation RMS " +
        cell(constant_placement["truth"]["segment_orientation_rms_deg"].get<double>()) + " deg");
    at_true_poses = calibration_at_true_poses_reference(setup, *simulated, *truth, settings.warmup);
    if (!at_true_poses.is_null())
      say("calibration at the true poses: segment orientation RMS " +
          cell(at_true_poses["truth"]["segment_orientation_rms_deg"].get<double>()) + " deg");
    // The same fit with the tracker's model (calibrated unless --no-calibrate): how much of the
    // tracker's error its subject model explains, and how much its filtering adds.
    if (setup.model.marker_names() == simulated->subject.model.marker_names()) {
      sim::Subject tracked_subject = simulated->subject;
      tracked_subject.model = setup.model;
      model_fit = evaluation::compare_with_truth(
          setup.model, evaluation::true_subject_fit(tracked_subject, simulated->recording), *truth,
          settings.warmup);
      say("tracker-model fit: segment orientation RMS " + cell(model_fit->segment_orientation_rms_deg) +
          " deg");
      // The tracker itself with the subject the simulation drew: what a perfect calibration would
      // give this filter (and its smoother), so the loss splits into calibration and filtering.
      pipeline::Session true_setup = setup;
      true_setup.model = simulated->subject.model;
      const evaluation::MethodResult with_true_subject = evaluation::evaluate_method(
          true_setup, complete, pipeline::Method::s2kf, main_samples, truth_ptr, settings.warmup);
      true_subject_tracking = {{"s2kf", truth_json(*with_true_subject.truth)}};
      if (settings.smooth)
        true_subject_tracking["s2kf_smoothed"] = truth_json(evaluation::compare_with_truth(
            setup.model, smoothed_motion(true_setup), *truth, settings.warmup));
      say("S2KF with the true subject: segment orientation RMS " +
          cell(true_subject_tracking["s2kf"]["segment_orientation_rms_deg"].get<double>()) + " deg");
    }
    for (const json& r : identifiable)
      say("identifiable-subject fit (prior-only fraction " + r["prior_only_fraction"].dump() + ", " +
          std::to_string(r["reset_directions"].get<int>()) + " directions reset): segment orientation RMS " +
          cell(r["truth"]["segment_orientation_rms_deg"].get<double>()) + " deg");
  }
  if (settings.smooth && truth) {
    const io::MotionTable motion = smoothed_motion(setup);
    smoothed = evaluation::compare_with_truth(setup.model, motion, *truth, settings.warmup);
    error_by_time_hidden["s2kf_smoothed"] = hidden_time(motion);
    say("smoothed S2KF: segment orientation RMS " + cell(smoothed->segment_orientation_rms_deg) + " deg");
  }

  // The occlusion Monte Carlo.
  evaluation::OcclusionOptions occlusion_options;
  occlusion_options.runs = settings.runs;
  occlusion_options.seed = settings.seed;
  occlusion_options.samples = main_samples;
  const evaluation::OcclusionStudy study =
      evaluation::occlusion_monte_carlo(setup, complete, occlusion_options, settings.warmup, [&](int run) {
        if (!progress) return;
        if (terminal)
          std::cerr << "\revaluate: occlusion run " << run + 1 << "/" << settings.runs << std::flush;
        else if ((run + 1) % 10 == 0 || run + 1 == settings.runs)
          std::cerr << "evaluate: occlusion run " << run + 1 << "/" << settings.runs << "\n";
        if (terminal && run + 1 == settings.runs) std::cerr << "\n";
      });
  say("occlusion: " + cell(study.mean_hidden_overall) + " of " + std::to_string(study.markers) +
      " markers hidden on average; S2KF band up to " + cell(study.s2kf_worst_mm) + " mm after the warm-up");

  // The CSV series and the figures.
  const fs::path out(settings.out);
  fs::create_directories(out);
  const EvaluationSeries series{setup.rate_hz,     frames,         sweep, s2kf, baseline, study,
                                truth.has_value(), settings.warmup};
  std::vector<std::string> written = write_evaluation_series(out, series);
  std::vector<std::string> figure_problems;
  draw_evaluation_figures(out, series, written, figure_problems);

  // Summary.
  json occlusion_json = {
      {"runs", study.runs},
      {"seed", settings.seed},
      {"probability_per_frame", occlusion_options.occlusion.probability},
      {"mean_frames", occlusion_options.occlusion.mean_frames},
      {"markers", study.markers},
      {"mean_hidden_markers", study.mean_hidden_overall},
      {"max_hidden_markers", study.max_hidden},
      {"samples", main_samples},
      {"distance_against", "all recorded markers, hidden ones included"},
      {"baseline_handling",
       "the baseline leaves hidden markers out of its least-squares fit (the paper's converter could not "
       "handle missing markers and was not run with occlusion)"}};
  auto band_json = [&](const evaluation::Band& band, const std::vector<double>& levels, double worst) {
    std::vector<double> after_max(
        band.max.begin() + std::min<long>(settings.warmup, static_cast<long>(band.max.size())),
        band.max.end());
    std::vector<double> after_mean(
        band.mean.begin() + std::min<long>(settings.warmup, static_cast<long>(band.mean.size())),
        band.mean.end());
    return json{{"mean_after_warmup_mm", number_or_null(track::mean_from(after_mean, 0))},
                {"band_max_after_warmup_mm", number_or_null(worst)},
                {"band_max_median_after_warmup_mm", number_or_null(track::quantile(after_max, 0.5))},
                {"run_level_mm",
                 {{"mean", number_or_null(track::mean_from(levels, 0))},
                  {"min", number_or_null(track::quantile(levels, 0))},
                  {"max", number_or_null(track::quantile(levels, 1))}}}};
  };
  occlusion_json["s2kf"] = band_json(study.s2kf, study.s2kf_level, study.s2kf_worst_mm);
  occlusion_json["baseline"] = band_json(study.baseline, study.baseline_level, study.baseline_worst_mm);
  json sweep_json = json::array();
  for (const auto& r : sweep) sweep_json.push_back(result_json(r));
  json summary = {{"recording", recording_path},
                  {"truth", truth ? json(truth_path) : json(nullptr)},
                  {"frames", frames},
                  {"frames_in_recording", recorded_frames},
                  {"rate_hz", setup.rate_hz},
                  {"height_mm", setup.height_mm},
                  {"markers", setup.mapping.markers_used()},
                  {"marker_set", setup.marker_set.name},
                  {"calibrated", setup.calibration.has_value()},
                  {"gain", settings.gain},
                  {"hidden_marker_frames_in_input", hidden_in_input},
                  {"warmup_frames", settings.warmup},
                  {"machine", machine_name()},
                  {"s2kf", result_json(s2kf)},
                  {"baseline", result_json(baseline)},
                  {"occlusion", occlusion_json},
                  {"sample_sweep", sweep_json},
                  {"true_subject_reference", reference ? truth_json(*reference) : json(nullptr)},
                  {"identifiable_subject_reference", simulated ? identifiable : json(nullptr)},
                  {"tracker_model_reference", model_fit ? truth_json(*model_fit) : json(nullptr)},
                  {"true_subject_tracking_reference", true_subject_tracking},
                  {"constant_placement_reference", constant_placement},
                  {"calibration_at_true_poses_reference", at_true_poses},
                  {"s2kf_smoothed", smoothed ? truth_json(*smoothed) : json(nullptr)},
                  {"error_by_time_hidden", error_by_time_hidden},
                  {"files", written},
                  {"figure_problems", figure_problems},
                  {"seconds", elapsed()}};
  io::write_file_atomically(out / "summary.json", [&](std::ostream& o) { o << summary.dump(2) << "\n"; });
  for (const std::string& problem : figure_problems) std::cerr << "s2kf evaluate: " << problem << "\n";
  if (!settings.quiet) {
    std::cout << "S2KF (L = " << main_samples << "): converged at frame " << s2kf.converged_frame
              << ", mean marker distance " << cell(s2kf.level_mm) << " mm, median " << cell(s2kf.median_ms)
              << " ms per frame.\nBaseline: converged at frame " << baseline.converged_frame
              << ", mean marker distance " << cell(baseline.level_mm) << " mm, median "
              << cell(baseline.median_ms) << " ms per frame.\nOcclusion (" << study.runs << " runs, "
              << cell(study.mean_hidden_overall) << " of " << study.markers
              << " markers hidden on average): S2KF up to " << cell(study.s2kf_worst_mm) << " mm after frame "
              << settings.warmup << ".\n";
    if (s2kf.truth) {
      const auto beside = [&](const char* what, double value, double ref, const char* unit) {
        std::cout << "  " << what << " " << cell(value) << " " << unit;
        if (reference) std::cout << " (true-subject fit " << cell(ref) << ")";
        std::cout << "\n";
      };
      const evaluation::TruthComparison& t = *s2kf.truth;
      const evaluation::TruthComparison r = reference ? *reference : evaluation::TruthComparison{};
      std::cout << "Against the truth after frame " << settings.warmup << ", S2KF:\n";
      beside("segment orientation RMS", t.segment_orientation_rms_deg, r.segment_orientation_rms_deg, "deg");
      beside("limb flexion RMS", t.limb_flexion_rms_deg, r.limb_flexion_rms_deg, "deg");
      beside("root orientation RMS", t.root_orientation_rms_deg, r.root_orientation_rms_deg, "deg");
      beside("joint-limit violations", static_cast<double>(t.joint_limit_violations),
             static_cast<double>(r.joint_limit_violations), "");
      if (smoothed)
        std::cout << "  smoothed: segment orientation RMS " << cell(smoothed->segment_orientation_rms_deg)
                  << " deg, limb flexion RMS " << cell(smoothed->limb_flexion_rms_deg)
                  << " deg, root orientation RMS " << cell(smoothed->root_orientation_rms_deg) << " deg\n";
    }
    std::cout << "Wrote " << written.size() << " files and summary.json to " << out.string() << ".\n";
  }
}

}  // namespace s2kf::cli
