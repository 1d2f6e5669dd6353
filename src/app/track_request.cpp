// One tracking request from a recording to a tracked motion and its summary (app/track_request.hpp).
#include <s2kf/app/track_request.hpp>

#include <s2kf/app/calibrated_subject.hpp>
#include <s2kf/app/inferred_marker_set.hpp>
#include <s2kf/app/sample_sets.hpp>
#include <s2kf/app/static_stretch_subject.hpp>
#include <s2kf/app/track_summary.hpp>
#include <s2kf/app/user_error.hpp>

#include <s2kf/body/reference_poses.hpp>
#include <s2kf/calibration/static_trial_markers.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/track/segment_observation.hpp>
#include <s2kf/track/tracking_smoother.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace s2kf::app {
namespace {

/// Whether the static trial's pose (--static-pose; empty: the nearest reference pose) stands upright.
bool standing_pose(const std::string& static_pose_name) {
  return static_pose_name.empty() || body::is_reference_pose(static_pose_name);
}

/// The static trial's posture where markers were placed by their motion (static_posture "auto"):
/// every frame held exactly within kPlacedMarkersStaticSdDeg of the reference pose, the pelvis
/// upright within the same SD where the pose is a standing reference pose (not a pose CSV, which
/// may sit or lean). Only the pose held gives a cluster's segment the zero of its joint angles, and
/// only the lab's vertical the body's tilt against its markers (docs/marker-sets.md).
void hold_placed_markers_posture(SubjectSettings& settings) {
  settings.static_posture = "exact";
  settings.static_sd_deg = std::min(settings.static_sd_deg, kPlacedMarkersStaticSdDeg);
  if (standing_pose(settings.static_pose_name)) settings.static_upright_sd_deg = settings.static_sd_deg;
}

/// The recording's frames the calibration reads (pipeline::calibration_stretches), one after another.
MarkerSequence calibration_frames_of(FrameSource& source, const pipeline::SessionOptions& options) {
  MarkerSequence frames;
  for (const auto& [first, count] : pipeline::calibration_stretches(
           source.frame_count(), options.calibration_frames, options.calibration_windows))
    frames.append_frames(read_frames(source, first, count));
  return frames;
}

/// Whether the marker labelled `label` was placed by its motion in the recording (not named by the set).
bool placed_by_motion(const std::vector<markerset::CompletedMarker>& placed, const std::string& label) {
  return std::any_of(placed.begin(), placed.end(),
                     [&](const markerset::CompletedMarker& m) { return m.label == label; });
}

/// Leaves out of `static_trial` (blanks the labels of) the markers whose distances to the others on
/// their segment are not the recording's (calibration::markers_moved_between_trials, `placed`: the
/// markers placed by their motion, the others named by the set): another
/// marker under the same label, as a capture system's numbering of unidentified points gives, or
/// one moved between the trials. Returns the sentence that names them, "" when none.
std::string leave_out_moved_markers(MarkerSequence& static_trial, const std::string& static_path,
                                    const body::MarkerSet& set,
                                    const std::vector<markerset::CompletedMarker>& placed,
                                    FrameSource& source, const pipeline::SessionOptions& options) {
  const body::BodyModel model = body::apply_marker_set(body::mmm_body_model(set.reference_height_mm), set);
  const body::MarkerMapping static_mapping = body::map_marker_set(static_trial.labels, set);
  std::vector<bool> named;  // the set's own markers, not placed by their motion
  for (const body::Marker& marker : model.markers) named.push_back(!placed_by_motion(placed, marker.name));
  const std::vector<calibration::MovedMarker> moved = calibration::markers_moved_between_trials(
      model, static_mapping, static_trial, body::map_marker_set(source.labels(), set),
      calibration_frames_of(source, options), named);
  if (moved.empty()) return "";
  std::ostringstream text;
  text << "the static trial " << std::filesystem::path(static_path).filename().string() << " leaves out "
       << moved.size()
       << " marker(s) whose distances to the markers on their segment differ from the recording's "
          "(another marker under the same label, or moved between the trials; by how much):";
  for (const calibration::MovedMarker& m : moved) {
    const auto point =
        static_cast<std::size_t>(static_mapping.point_of_marker[static_cast<std::size_t>(m.marker)]);
    text << " " << static_trial.labels[point] << " "
         << (std::isfinite(m.mismatch_mm) ? std::to_string(std::lround(m.mismatch_mm)) + " mm"
                                          : "(no pair to check)");
    static_trial.labels[point].clear();
    static_trial.visible.row(static_cast<Eigen::Index>(point)).setConstant(false);
  }
  return text.str();
}

/// Whether a segment of the static trial carries markers placed by their motion and none the set
/// names: only the pose held then gives that segment the zero of its joint angles.
bool shows_cluster_segment(const MarkerSequence& static_trial, const MarkerSetChoice& choice) {
  const body::BodyModel model =
      body::apply_marker_set(body::mmm_body_model(choice.set.reference_height_mm), choice.set);
  std::vector<int> point_segment;
  const body::MarkerMapping mapping = body::map_marker_set(static_trial.labels, choice.set);
  const track::SegmentObservation segments = track::observe_segments(model, mapping, &point_segment);
  std::vector<bool> placed(segments.segments.size(), false), named(segments.segments.size(), false);
  for (std::size_t p = 0; p < point_segment.size() && p < static_trial.labels.size(); ++p) {
    if (point_segment[p] < 0 || !static_trial.visible.row(static_cast<Eigen::Index>(p)).any()) continue;
    (placed_by_motion(choice.inferred, static_trial.labels[p])
         ? placed
         : named)[static_cast<std::size_t>(point_segment[p])] = true;
  }
  for (std::size_t s = 0; s < placed.size(); ++s)
    if (placed[s] && !named[s]) return true;
  return false;
}

/// With static_posture "auto", where a segment of the static trial carries only markers placed by
/// their motion (shows_cluster_segment): the posture held exactly (hold_placed_markers_posture), as
/// only the pose held gives that segment the zero of its joint angles. Returns whether it is.
bool hold_posture_for_placed_markers(const TrackRequest& request, const MarkerSequence& static_trial,
                                     const MarkerSetChoice& choice, SubjectSettings& settings) {
  if (request.static_posture != "auto" || !shows_cluster_segment(static_trial, choice)) return false;
  hold_placed_markers_posture(settings);
  return true;
}

/// `value` as few digits as say it ("1750", "0.5").
std::string number_text(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

bool one_of(const std::string& value, std::initializer_list<const char*> allowed) {
  return std::any_of(allowed.begin(), allowed.end(), [&](const char* a) { return value == a; });
}

/// "'x' or 'y'" as the front end quotes values.
std::string choices(std::initializer_list<const char*> allowed) {
  std::string text;
  std::size_t i = 0;
  for (const char* a : allowed) {
    text += (i == 0 ? "" : i + 1 == allowed.size() ? " or " : ", ") + std::string("'") + a + "'";
    ++i;
  }
  return text;
}

}  // namespace

std::string option_name(const TrackRequest& request, const std::string& dashed) {
  if (request.names == OptionNames::program) return "--" + dashed;
  std::string name = dashed;
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

std::string deprecation_warning(const TrackRequest& request) {
  if (!request.static_refine) return "";
  return option_name(request, "static-refine") + " is deprecated: calibrating the static trial and the " +
         "recording together is what " + option_name(request, "static") + " does now (" +
         option_name(request, "static-alone") + " calibrates on the static trial alone)";
}

std::string not_a_body_remedy(const TrackRequest& request) {
  return request.names == OptionNames::program
             ? "give a marker set with --markerset, or track it anyway with --force"
             : "give a marker set with markerset=..., or track it anyway with force=True";
}

void check_request(const TrackRequest& r) {
  const auto name = [&](const std::string& dashed) { return option_name(r, dashed); };
  if (r.samples < 3 || r.samples > 100001)
    throw UserError(name("samples") + " must lie between 3 and 100001, got " + std::to_string(r.samples));
  if (r.calibration_samples != 0 && (r.calibration_samples < 3 || r.calibration_samples > 100001))
    throw UserError(name("calibration-samples") + " must lie between 3 and 100001 (or be 0: " +
                    name("samples") + "), got " + std::to_string(r.calibration_samples));
  if (r.height_mm != 0 && !(r.height_mm >= 300 && r.height_mm <= 3000))
    throw UserError(name("height") + " must lie between 300 and 3000 mm (or be 0: estimated), got " +
                    number_text(r.height_mm));
  if (!(r.static_sd_deg >= 0.1 && r.static_sd_deg <= 90.0))
    throw UserError(name("static-sd") + " must lie between 0.1 and 90 degrees");
  if (r.calibration_frames < 10 || r.calibration_frames > 10000000)
    throw UserError(name("calibration-frames") + " must lie between 10 and 10000000");
  if (!(r.calibration_shrink >= 0 && r.calibration_shrink <= 1e6))
    throw UserError(name("calibration-shrink") + " must lie in [0, 1e6]");
  if (!one_of(r.preset, {"default", "paper"}))
    throw UserError("unknown preset '" + r.preset + "' (use " + choices({"default", "paper"}) + ")");
  if (!one_of(r.motion_model, {"random-walk", "constant-velocity"}))
    throw UserError("unknown motion model '" + r.motion_model + "' (use " +
                    choices({"random-walk", "constant-velocity"}) + ")");
  if (r.gain == "information-form-root-products")
    throw UserError(
        "the gain 'information-form-root-products' was removed: no measurement showed it the best choice for "
        "any case (docs/tracking.md, the gain); use 'square-root' (the exact update) or the default "
        "'information-form'");
  if (!one_of(r.gain, {"information-form", "square-root"}))
    throw UserError("unknown gain '" + r.gain + "' (use " + choices({"information-form", "square-root"}) +
                    ")");
  if (!one_of(r.method, {"s2kf", "baseline"}))
    throw UserError(name("method") + " must be 's2kf' or 'baseline', not '" + r.method + "'");
  if (r.smooth && r.method != "s2kf")
    throw UserError(name("smooth") + " works on the S2KF's estimates; it cannot be combined with " +
                    (r.names == OptionNames::program ? "--method baseline" : "method='baseline'"));
  if (!(r.smoothing_memory_limit_bytes > 0))
    throw UserError("the smoothing memory limit must be a positive number of bytes");
  if (!r.markerset.empty() && !r.subject.empty())
    throw UserError("give " + name("markerset") + " or " + name("subject") +
                    ", not both (a subject file is a calibrated marker set)");
  if (!r.static_trial.empty() && !r.subject.empty())
    throw UserError("give " + name("static") + " or " + name("subject") + ", not both (" + name("static") +
                    " calibrates the subject on the static trial)");
  if (!one_of(r.static_posture, {"auto", "near", "exact"}))
    throw UserError(name("static-posture") + " must be " + choices({"auto", "near", "exact"}) + ", not '" +
                    r.static_posture + "'");
  if (r.static_refine && r.static_trial.empty())
    throw UserError(name("static-refine") +
                    " calibrates the static trial and the recording together; it needs " + name("static"));
  if (r.static_alone && r.static_trial.empty())
    throw UserError(name("static-alone") + " calibrates the subject on the static trial alone; it needs " +
                    name("static"));
  if (r.static_alone && r.static_refine)
    throw UserError("give " + name("static-alone") + " or " + name("static-refine") + ", not both (" +
                    name("static-refine") + " is what " + name("static") + " does without " +
                    name("static-alone") + ")");
  if (!r.static_trial.empty() && !r.calibrate)
    throw UserError(name("static") +
                    " calibrates the subject on the static trial; it cannot be combined with " +
                    (r.names == OptionNames::program ? "--no-calibrate" : "calibrate=False"));
}

track::TrackerOptions tracker_options(const TrackRequest& request, double rate_hz) {
  track::TrackerOptions options;
  try {
    options = track::preset_options(request.preset, rate_hz);
  } catch (const std::invalid_argument& e) {
    throw UserError(e.what());
  }
  options.samples = request.samples;
  options.motion_model = track::motion_model_from_name(request.motion_model);
  track::set_gain_from_name(options, request.gain);
  return options;
}

pipeline::SessionOptions session_options(const TrackRequest& request, double rate_hz) {
  pipeline::SessionOptions options;
  options.tracker = tracker_options(request, rate_hz);
  options.height_mm = request.height_mm;
  // With a static trial the recording is calibrated together with it, unless static_alone.
  options.calibrate = request.calibrate && request.subject.empty() && !request.static_alone;
  options.calibration_frames = request.calibration_frames;
  options.calibration.weak_direction_shrink = request.calibration_shrink;
  options.calibration.threads = request.calibration_threads > 0 ? request.calibration_threads : every_core();
  options.noise_from_calibration = !request.uniform_noise;
  return options;
}

PreparedTrack prepare_track(FrameSource& source, const RecordingDescription& recording,
                            const TrackRequest& request) {
  check_request(request);
  const std::string& input = recording.input;
  const std::int64_t frames = source.frame_count();
  if (frames == 0) throw UserError(input + ": the recording holds no complete frame");
  PreparedTrack prepared;
  prepared.input = input;
  const std::string truth_option = option_name(request, "truth");
  // Ground truth, read before tracking so a wrong file fails fast.
  if (!request.truth.empty()) {
    try {
      prepared.truth = io::load_motion_csv(request.truth);
    } catch (const std::exception& e) {
      throw UserError(truth_option + ": " + e.what());
    }
    if (prepared.truth->frames() != frames)
      throw UserError(truth_option + ": " + request.truth + " has " +
                      std::to_string(prepared.truth->frames()) + " rows, but " + input + " has " +
                      std::to_string(frames) + " frames");
  }
  const bool with_rates = request.motion_model == "constant-velocity";
  const double smoothing_bytes =
      static_cast<double>(frames) * static_cast<double>(track::TrackingSmoother::bytes_per_frame(with_rates));
  if (request.smooth && smoothing_bytes > request.smoothing_memory_limit_bytes)
    throw UserError(input + ": " + std::to_string(frames) + " frames are too many to smooth in memory (" +
                    fixed_text(smoothing_bytes / 1e9, 1) + " GB); track without " +
                    option_name(request, "smooth") + ", or split the recording");

  pipeline::SessionOptions options = session_options(request, source.rate_hz());
  prepared.samples = cached_sample_set(46, request.samples);
  // The set the request names, or the best bundled match completed (a file: inferred where none fits).
  double marker_set_seconds = 0;  // the summary's marker_set stage
  const auto choose_set = [&] {
    const auto start = std::chrono::steady_clock::now();
    MarkerSetChoice choice =
        recording.readable_file
            ? choose_or_infer_marker_set(input, source.labels(), request.markerset, request.subject,
                                         recording.inferred_markerset_path, request.force,
                                         not_a_body_remedy(request))
            : choose_marker_set_for(source.labels(), request.markerset, request.subject);
    marker_set_seconds += track::seconds_since(start);
    return choice;
  };
  std::string static_message;  // the static trial's markers left out (leave_out_moved_markers)
  if (!request.static_trial.empty() && !request.static_alone) {
    // The static trial and the recording calibrated together (one bundle adjustment from the
    // marker set): the static frames fix the gauges, the moving ones what bending joints show.
    // The static trial read first: one that cannot be read stops the run before the inferred
    // marker set's file is written.
    options.static_trial = read_static_trial(request);
    prepared.choice = choose_set();  // no subject beside a static trial (check_request)
    SubjectSettings settings = static_trial_settings(request);
    static_message = leave_out_moved_markers(options.static_trial, request.static_trial, prepared.choice.set,
                                             prepared.choice.inferred, source, options);
    // Where the set's named markers ride on every segment the static trial shows, they give the
    // zeros of the joint angles and the posture is estimated; else it is held, as calibrate_static_trial
    // does.
    hold_posture_for_placed_markers(request, options.static_trial, prepared.choice, settings);
    apply_static_settings(settings, options.calibration);
    // The static trial, not the template fit that placed them, decides where such markers sit along
    // their segments' gauges (calibration::CalibrationOptions::placed_by_motion).
    for (const body::MarkerSetEntry& entry : prepared.choice.set.entries)
      options.calibration.placed_by_motion.push_back(placed_by_motion(prepared.choice.inferred, entry.label));
    options.calibration_may_fail = false;
    prepared.choice.source += "; calibrated together with the static trial " + request.static_trial;
  } else if (!request.static_trial.empty()) {
    // The subject calibrated on the static trial (`s2kf calibrate --static`), with the markers the
    // set does not name placed by the recording's motion first (a static trial shows none), then
    // the recording tracked with it as with a subject file.
    const auto start = std::chrono::steady_clock::now();
    const std::optional<MarkerSetChoice> completed =
        recording.readable_file
            ? completed_set_for_static_trial(request, input, recording.inferred_markerset_path)
            : std::nullopt;
    marker_set_seconds += track::seconds_since(start);
    StaticTrialPlacedMarkers placed;
    const CalibratedSubject calibrated = calibrate_static_trial(
        request, prepared.samples, std::filesystem::path(input).stem().string() + "_subject",
        completed ? &*completed : nullptr, input, &placed);
    static_message = placed.left_out;
    prepared.choice.set = calibrated.subject;
    prepared.choice.source = "calibrated on the static trial " + request.static_trial;
    if (placed.held_exactly)
      prepared.choice.source +=
          " with the posture held exactly, within " +
          number_text(std::min(request.static_sd_deg, kPlacedMarkersStaticSdDeg)) +
          " deg (markers were placed by their motion, and only the pose held gives their segments "
          "the zero of the joint angles)";
    if (completed) {
      prepared.choice.source += "; " + completed->source;
      prepared.choice.inferred = completed->inferred;
      prepared.choice.left_out = completed->left_out;
    }
  } else {
    prepared.choice = choose_set();
  }
  if (options.calibrate && request.calibration_samples > 0 && request.calibration_samples != request.samples)
    options.calibration_samples = cached_sample_set(46, request.calibration_samples);
  std::string stretch_message;  // a static trial found inside the recording (static_stretch_subject.hpp)
  if (request.static_stretch && options.calibrate && request.static_trial.empty() && frames > 0) {
    StretchSubject stretch = static_stretch_subject(source, input, prepared.choice, request, prepared.samples,
                                                    options.calibration.threads);
    if (stretch.subject) {  // calibrated together with the recording, as --static does
      apply_static_settings(static_trial_settings(request), options.calibration);
      // Its frames are the recording's own, among its calibration frames too: each keeps its weight
      // (counted as its postures, test1's stretch tracked at 2.84 mm instead of 2.65).
      options.calibration.static_distinct_mm = 0;
      options.static_trial = std::move(stretch.frames);
    }
    stretch_message = stretch.message;
  }
  pipeline::Session& session = prepared.session;
  try {
    session = pipeline::prepare_session(source, prepared.choice.set, options, prepared.samples);
  } catch (const std::invalid_argument& e) {
    throw UserError(input + ": " + e.what());
  }
  session.times.marker_set = marker_set_seconds;
  if (prepared.truth && prepared.truth->joint_names != session.model.joint_names())
    throw UserError(
        truth_option + ": " + request.truth + " does not have the " +
        std::to_string(session.model.joint_count()) +
        " joint columns of the body model (write it with s2kf simulate, whose _truth.csv has them)");
  // Model outputs never match a marker; the summary lists each under its own name in the file.
  // The ignored labels are in point order, one per unmatched point, "" for every model output.
  std::vector<std::string> output_names;
  for (std::size_t p = 0; p < recording.raw_labels.size() && p < source.labels().size(); ++p)
    if (source.labels()[p].empty()) output_names.push_back(recording.raw_labels[p]);
  std::size_t next_output = 0;
  for (std::string& label : session.mapping.ignored_labels)
    if (label.empty() && next_output < output_names.size()) label = output_names[next_output++];
  prepared.warnings = recording.file_warnings;
  prepared.warnings.insert(prepared.warnings.end(), session.warnings.begin(), session.warnings.end());
  prepared.messages = marker_set_messages(prepared.choice, session.mapping);
  if (!static_message.empty())
    prepared.messages.push_back(std::filesystem::path(input).filename().string() + ": " + static_message);
  if (!stretch_message.empty())
    prepared.messages.push_back(std::filesystem::path(input).filename().string() + ": " + stretch_message);
  return prepared;
}

std::optional<nlohmann::json> joint_subject_document(const PreparedTrack& prepared,
                                                     const track::TrackingRun& run,
                                                     const TrackRequest& request, const std::string& name) {
  if (request.static_trial.empty() || request.static_alone || !prepared.session.calibration)
    return std::nullopt;
  const calibration::SubjectCalibration& calibration = *prepared.session.calibration;
  body::MarkerSet subject =
      subject_marker_set(prepared.choice.set, calibration.model, calibration.segment_scale,
                         prepared.session.tracker.marker_noise_mm_per_marker, name);
  subject.description =
      "subject calibrated by s2kf track --static from the marker set " + prepared.choice.set.name;
  return subject_document(subject, calibration.mean_marker_distance_before_mm,
                          pipeline::calibrated_distance_mm(prepared.session, run),
                          std::filesystem::path(request.static_trial).filename().string() + " and " +
                              std::filesystem::path(prepared.input).filename().string());
}

track::TrackingRun run_track(PreparedTrack& prepared, FrameSource& source, const TrackRequest& request,
                             const pipeline::RunHooks& hooks, bool bounded_memory) {
  pipeline::RunOptions run_options;
  run_options.method = request.method == "s2kf" ? pipeline::Method::s2kf : pipeline::Method::baseline;
  run_options.smooth = request.smooth;
  run_options.bounded_memory = bounded_memory;
  track::TrackingRun run;
  const pipeline::Session& session = prepared.session;
  try {
    run = pipeline::run_session(session, source, prepared.samples, run_options, hooks);
  } catch (const std::invalid_argument& e) {
    throw UserError(prepared.input + ": " + e.what());
  }
  if (run.frames_tracked == 0)
    throw UserError(prepared.input + ": no frame has the " +
                    std::to_string(session.tracker.min_markers_to_start) +
                    " visible markers needed to start tracking");
  if (2 * run.frames_prediction_only > run.frames_tracked)
    throw UserError(prepared.input + ": the filter's update failed in " +
                    std::to_string(run.frames_prediction_only) + " of " + std::to_string(run.frames_tracked) +
                    " tracked frames, which only repeat its prediction; no result is written (" +
                    (run.warnings.empty() ? std::string("see the header and labels") : run.warnings.front()) +
                    ")");
  prepared.warnings.insert(prepared.warnings.end(), run.warnings.begin(), run.warnings.end());
  return run;
}

nlohmann::json summarize_track(const PreparedTrack& prepared, const track::TrackingRun& run,
                               const TrackRequest& request, const io::MotionTable* motion,
                               const track::StageTimes& outside) {
  nlohmann::json summary =
      track_summary(prepared.input, request.method, prepared.choice, prepared.messages, prepared.session, run,
                    request.smooth, prepared.warnings, request.calibration_shrink, outside);
  if (prepared.truth) {
    // Accuracy from the frames after the filter's start-up.
    std::optional<evaluation::TruthComparison> accuracy;
    try {
      accuracy = evaluation::compare_with_truth(prepared.session.model, motion ? *motion : run.motion,
                                                *prepared.truth, kTruthWarmupFrames);
    } catch (const std::invalid_argument& e) {
      throw UserError(option_name(request, "truth") + ": " + request.truth + ": " + e.what());
    }
    summary["truth"] = truth_json(*accuracy);
    summary["truth"]["warmup_frames"] = kTruthWarmupFrames;
  }
  return summary;
}

std::unique_ptr<c3d::C3dFrameSource> open_static_trial(const TrackRequest& request) {
  const std::string what = option_name(request, "static");
  std::unique_ptr<c3d::C3dFrameSource> source;
  try {
    source = std::make_unique<c3d::C3dFrameSource>(request.static_trial);
  } catch (const std::exception& e) {
    throw UserError(what + ": " + e.what());
  }
  if (source->frame_count() == 0)
    throw UserError(what + ": " + request.static_trial + " holds no complete frame");
  return source;
}

MarkerSequence read_static_trial(const TrackRequest& request) {
  const std::unique_ptr<c3d::C3dFrameSource> source = open_static_trial(request);
  try {
    return read_frames(*source, 0, std::min<std::int64_t>(source->frame_count(), kStaticTrialMaxFrames));
  } catch (const UserError&) {
    throw;
  } catch (const std::exception& e) {
    throw UserError(option_name(request, "static") + ": " + e.what());
  }
}

SubjectSettings static_trial_settings(const TrackRequest& request) {
  SubjectSettings settings = static_trial_settings(
      request.markerset, request.height_mm, !request.uniform_noise, request.static_sd_deg,
      request.static_pose, request.static_posture == "auto" ? std::string("near") : request.static_posture);
  settings.static_pose_option = option_name(request, "static-pose");
  return settings;
}

CalibratedSubject calibrate_static_trial(const TrackRequest& request, const SampleSet& samples,
                                         const std::string& name, const MarkerSetChoice* completed,
                                         const std::string& recording, StaticTrialPlacedMarkers* placed) {
  SubjectSettings settings = static_trial_settings(request);
  if (!completed)
    return calibrate_subject_file(request.static_trial, option_name(request, "static"), settings, samples,
                                  name);
  settings.set = completed->set;
  MarkerSequence trial = read_static_trial(request);
  StaticTrialPlacedMarkers done;
  if (!recording.empty()) {
    std::unique_ptr<c3d::C3dFrameSource> source;
    try {
      source = std::make_unique<c3d::C3dFrameSource>(recording);
    } catch (const std::exception& e) {
      throw UserError(e.what());
    }
    done.left_out = leave_out_moved_markers(trial, request.static_trial, completed->set, completed->inferred,
                                            *source, session_options(request, source->rate_hz()));
  }
  // Markers placed by their motion (clusters) get the zero of their joint angles from the pose held:
  // held exactly and tightly, or the posture trades with their offsets (docs/marker-sets.md).
  done.held_exactly = hold_posture_for_placed_markers(request, trial, *completed, settings);
  if (placed) *placed = done;
  SequenceFrameSource source(trial);
  return calibrate_subject(source, option_name(request, "static") + " " + request.static_trial, settings,
                           samples, name);
}

std::optional<MarkerSetChoice> completed_set_for_static_trial(const TrackRequest& request,
                                                              const std::string& recording_path,
                                                              const std::string& completed_path) {
  // A static trial that cannot be read stops the run before the completed set's file is written.
  open_static_trial(request);
  std::vector<std::string> labels;
  try {
    labels = c3d::C3dFrameSource(recording_path).labels();
  } catch (const std::exception& e) {
    throw UserError(e.what());
  }
  MarkerSetChoice choice =
      choose_or_infer_marker_set(recording_path, labels, request.markerset, "", completed_path, request.force,
                                 not_a_body_remedy(request));
  if (choice.inferred.empty()) return std::nullopt;
  return choice;
}

}  // namespace s2kf::app
