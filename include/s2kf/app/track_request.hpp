/// @file
/// One tracking request, whatever the front end: every option of `s2kf track` that decides the
/// numbers (marker set, subject, calibration, tracker, smoothing, truth) with its default, its
/// checks, and the steps from a recording to a tracked motion and its summary. `s2kf track` and the
/// Python module's `s2kf.track`, `s2kf.Tracker` and `s2kf.calibrate` are adapters over it.
#pragma once

#include <s2kf/app/calibrated_subject.hpp>
#include <s2kf/app/marker_set_json.hpp>

#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/stage_times.hpp>
#include <s2kf/track/tracking_run.hpp>

#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace s2kf::app {

/// The default tracker options (the "default" preset), for the defaults below.
inline const track::TrackerOptions kDefaultTracker{};

/// How messages name the options: as the program's options ("--static-sd") or as Python's
/// keywords ("static_sd").
enum class OptionNames { program, python };

/// The SD (degrees) within which static_posture "auto" holds a static trial's posture to the
/// reference pose where markers were placed by their motion (at most static_sd_deg): looser, the
/// posture trades with their offsets (the cluster model's knees 0.5-0.9 deg worse on squats).
inline constexpr double kPlacedMarkersStaticSdDeg = 0.5;

struct TrackRequest {
  // The marker set: at most one of markerset, subject, static_trial.
  std::string markerset;       ///< a bundled set's name or a .json file; empty: the best bundled match
  std::string subject;         ///< a calibrated subject file (`s2kf calibrate`)
  std::string static_trial;    ///< a C3D static trial: the subject is calibrated on it first
  double static_sd_deg = 3.0;  ///< how far (SD, degrees) each joint may be from the reference pose there
  /// The pose held in the static trial (or a static stretch): zero, t-pose, a-pose or a pose CSV
  /// (its first row); empty: the reference pose nearest the tracked posture.
  std::string static_pose;
  /// "near": the posture held is estimated within static_sd_deg of the reference pose; "exact":
  /// every frame's angles within static_sd_deg of it; "auto": exact, within
  /// kPlacedMarkersStaticSdDeg and the pelvis upright within as much, where a segment of the static
  /// trial carries only markers placed by their motion (a cluster's zero comes from the pose held
  /// alone), else near.
  std::string static_posture = "auto";
  /// With a static trial: calibrate the subject on the static trial alone and track with it as with
  /// a subject file, instead of calibrating the static trial and the recording together (one
  /// bundle adjustment from the marker set: the static frames with the posture's prior, the
  /// recording's without), which the static trial does by default.
  bool static_alone = false;
  /// Deprecated: the joint calibration is what static_trial does now (its former option,
  /// `--static-refine`, still needs static_trial and contradicts static_alone).
  bool static_refine = false;
  /// Without a static trial: a stretch of the recording in which the subject stands still in a
  /// reference pose is its static trial, and the recording's calibration starts from it.
  bool static_stretch = true;
  double height_mm = 0;  ///< 0: the marker set's, else estimated from rigid marker pairs
  // The subject's calibration on the recording itself (not with a subject or static trial).
  bool calibrate = true;
  long calibration_frames = 1200;  ///< frames used, in stretches spread over the recording
  int calibration_samples = 0;     ///< samples of the calibration's tracking pass; 0: `samples`
  double calibration_shrink = calibration::CalibrationOptions{}.weak_direction_shrink;
  bool uniform_noise = false;   ///< every marker the same noise (else each its calibration residual's)
  int calibration_threads = 0;  ///< 0: every core (one recording); a batch gives 1 per recording
  // The tracker.
  int samples = kDefaultTracker.samples;     ///< S2KF sample count L
  std::string preset = "default";            ///< or "paper" (the seed paper's noise, for comparison)
  std::string motion_model = "random-walk";  ///< or "constant-velocity"
  std::string gain = "information-form";     ///< or "square-root" (the exact update)
  std::string method = "s2kf";               ///< or "baseline" (per-frame Levenberg-Marquardt)
  bool smooth = false;                       ///< offline Rauch-Tung-Striebel smoothing
  /// Memory smoothing may take (it keeps every frame's posterior) before a recording is refused.
  double smoothing_memory_limit_bytes = 8e9;
  std::string truth;   ///< a ground-truth motion CSV (s2kf simulate's _truth.csv): accuracy in the summary
  bool force = false;  ///< track even a recording whose inferred marker set does not look like a whole body
  OptionNames names = OptionNames::program;  ///< not an option: the front end's spelling in messages
};

/// `dashed` ("static-sd") as the request's front end spells it: "--static-sd" or "static_sd".
std::string option_name(const TrackRequest& request, const std::string& dashed);

/// How a recording refused as no whole body (choose_or_infer_marker_set) is tracked all the same,
/// in the front end's words: the program's options or Python's keywords.
std::string not_a_body_remedy(const TrackRequest& request);

/// The warning a deprecated option of `request` gets, in the front end's words (what replaced
/// it), or "" when it uses none.
std::string deprecation_warning(const TrackRequest& request);

/// Frames left out of the accuracy against the truth (the filter's start-up).
inline constexpr long kTruthWarmupFrames = 20;

/// Throws UserError with one sentence naming the option when the request is out of range or
/// contradicts itself (what can be told without the recording). Options are named as the program
/// names them; Python's keywords are the same names with underscores.
void check_request(const TrackRequest& request);

/// The recording a request is applied to, besides its frames.
struct RecordingDescription {
  std::string input;                       ///< names the recording in messages and the summary
  std::vector<std::string> raw_labels;     ///< one per point (model outputs keep their names), or empty
  std::vector<std::string> file_warnings;  ///< the reader's
  /// Whether `input` is a C3D file the marker-set choice may read again: to place the labels the
  /// chosen set does not name by their motion, or to infer a set when no bundled set fits the
  /// labels. Else (arrays, live streams) the set's labels are mapped and the others ignored.
  bool readable_file = false;
  /// Where such a completed or inferred set is written (PREFIX_markerset.json); empty: not written.
  std::string inferred_markerset_path;
};

/// A recording prepared for tracking: the marker set and why, the session (model, mapping,
/// height, calibration), the samples, the truth, and what to tell the user so far.
struct PreparedTrack {
  std::string input;  ///< names the recording in messages and the summary
  MarkerSetChoice choice;
  pipeline::Session session;
  SampleSet samples;
  std::vector<std::string> messages;  ///< which marker set and why, labels ignored
  std::vector<std::string> warnings;  ///< the file's and the session's (the run adds its own)
  std::optional<io::MotionTable> truth;
};

/// The tracker options a request asks for at `rate_hz` (preset, samples, motion model, gain).
track::TrackerOptions tracker_options(const TrackRequest& request, double rate_hz);

/// The session options a request asks for (the tracker's, height, calibration).
pipeline::SessionOptions session_options(const TrackRequest& request, double rate_hz);

/// Checks the recording against the request (frames, rate, smoothing memory, truth), chooses the
/// marker set (with a static trial: calibrated together with the recording, or on the static trial
/// first with static_alone), and prepares the session.
/// Throws UserError naming the recording.
PreparedTrack prepare_track(FrameSource& source, const RecordingDescription& recording,
                            const TrackRequest& request);

/// The subject a static trial and the recording were calibrated together on (`--static` without
/// `--static-alone`) as a subject file's document named `name`, for `s2kf track --subject` (its
/// marker distance after calibrating: the run's); none when the recording was not calibrated with
/// a static trial.
std::optional<nlohmann::json> joint_subject_document(const PreparedTrack& prepared,
                                                     const track::TrackingRun& run,
                                                     const TrackRequest& request, const std::string& name);

/// Runs the prepared session over every frame (rows to `hooks.sink` when set, else kept in the
/// run's motion table); refuses a run that tracked nothing or only predicted. `bounded_memory`: a
/// stream of unknown length, whose per-frame series are kept for its first frames only
/// (pipeline::RunOptions::bounded_memory).
track::TrackingRun run_track(PreparedTrack& prepared, FrameSource& source, const TrackRequest& request,
                             const pipeline::RunHooks& hooks = {}, bool bounded_memory = false);

/// The summary of a run (PREFIX.json of `s2kf track`, `TrackResult.summary` in Python). With a
/// truth, the accuracy of `motion` (the run's motion as written or kept) against it.
nlohmann::json summarize_track(const PreparedTrack& prepared, const track::TrackingRun& run,
                               const TrackRequest& request, const io::MotionTable* motion = nullptr,
                               const track::StageTimes& outside = {});

/// The frames of a static trial read at most (a static calibration uses as many; 20 s at 60 Hz).
inline constexpr std::int64_t kStaticTrialMaxFrames = 1200;

/// The request's static trial opened (its header and parameters read, no frame); a UserError
/// naming the option when the file cannot be read or holds no frame.
std::unique_ptr<c3d::C3dFrameSource> open_static_trial(const TrackRequest& request);

/// The request's static trial read into memory (its first kStaticTrialMaxFrames frames); a
/// UserError naming the option when the file cannot be read or holds no frame.
MarkerSequence read_static_trial(const TrackRequest& request);

/// The settings of the request's static trial (or static stretch): its pose, SD and posture.
SubjectSettings static_trial_settings(const TrackRequest& request);

/// What calibrate_static_trial did with the markers placed by a recording's motion.
struct StaticTrialPlacedMarkers {
  std::string left_out;       ///< the sentence naming those the static trial left out, "" for none
  bool held_exactly = false;  ///< the posture held exactly (static_posture "auto", a cluster segment)
};

/// The subject calibrated on the request's static trial in the pose it names (or the one found
/// from the data), as `s2kf calibrate --static`, named `name`, with every core; with `completed`
/// (completed_set_for_static_trial on the C3D file `recording`) instead of the request's or the
/// best bundled set where given: the static trial then leaves out the placed markers its
/// distances do not confirm (as the joint calibration does), and `placed` (optional) says what was done.
CalibratedSubject calibrate_static_trial(const TrackRequest& request, const SampleSet& samples,
                                         const std::string& name, const MarkerSetChoice* completed = nullptr,
                                         const std::string& recording = "",
                                         StaticTrialPlacedMarkers* placed = nullptr);

/// With a static trial: when the C3D file at `recording_path`, tracked with it, has markers the
/// chosen set does not name (a cluster model), that set completed by their motion in the recording
/// (a static trial shows no motion to place them by) and written to `completed_path` (unless
/// empty), to calibrate the static trial with; nothing when there is nothing to place. A UserError,
/// and no file, when the static trial cannot be read.
std::optional<MarkerSetChoice> completed_set_for_static_trial(const TrackRequest& request,
                                                              const std::string& recording_path,
                                                              const std::string& completed_path);

}  // namespace s2kf::app
