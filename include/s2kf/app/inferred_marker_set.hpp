/// @file
/// A marker set inferred from a C3D recording (markerset::infer_marker_set, with the bundled sets as
/// the places labs put markers), written as a marker-set file a person can read and correct: what
/// `s2kf markerset infer` does, and what `s2kf track` falls back on when no bundled set names
/// enough of a recording's labels.
#pragma once

#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/app/sample_sets.hpp>
#include <s2kf/app/user_error.hpp>

#include <s2kf/body/marker_set_labels.hpp>
#include <s2kf/body/non_marker_points.hpp>
#include <s2kf/core/parallel_for.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/markerset/body_coverage.hpp>
#include <s2kf/markerset/marker_set_completion.hpp>
#include <s2kf/markerset/marker_set_inference.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace s2kf::app {

/// Samples of the inference's rounds of tracking: enough to place markers, faster than the
/// default 301.
inline constexpr int kInferenceSamples = 101;

/// The recording at `input` for inference; a UserError with the reader's sentence otherwise.
inline MarkerSequence read_recording_to_infer(const std::string& input) {
  try {
    return c3d::read_c3d(input);
  } catch (const std::exception& e) {
    throw UserError(e.what());
  }
}

/// Inference with the tracker at kInferenceSamples, the bundled sets as the known ones, on every
/// core.
inline markerset::MarkerSetInferenceOptions inference_options(int up_axis = -1) {
  markerset::MarkerSetInferenceOptions options;
  options.up_axis = up_axis;
  options.tracker.samples = kInferenceSamples;
  options.threads = every_core();
  for (const std::string& name : bundled_marker_set_names())
    options.known_sets.push_back(resolve_marker_set(name));
  return options;
}

/// `set` as a marker-set file at `path` (atomically, its folder made).
inline void write_marker_set_file(const std::string& path, const body::MarkerSet& set) {
  if (std::filesystem::path(path).has_parent_path())
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  io::write_file_atomically(path,
                            [&](std::ostream& stream) { stream << marker_set_to_json(set).dump(2) << "\n"; });
}

/// Infers a marker set for the recording at `input` and writes it to `out` (atomically; empty: not
/// written, the set named after the recording). `up_axis`:
/// 0-2, or -1 to find it. Throws UserError with one sentence when the recording cannot be read or
/// its markers cannot be placed unambiguously.
/// Where `not_a_body` is given and the inferred set does not look like a whole body
/// (markerset::whole_body_problem), the sentence goes there and nothing is written.
inline markerset::InferredMarkerSet infer_marker_set_file(const std::string& input, const std::string& out,
                                                          int up_axis, std::string* not_a_body = nullptr) {
  const MarkerSequence recording = read_recording_to_infer(input);
  const markerset::MarkerSetInferenceOptions options = inference_options(up_axis);
  markerset::InferredMarkerSet inferred;
  try {
    inferred = markerset::infer_marker_set(recording, cached_sample_set(46, kInferenceSamples), options);
  } catch (const std::invalid_argument& e) {
    throw UserError(input + ": no marker set can be inferred: " + e.what());
  }
  if (not_a_body) {
    *not_a_body =
        markerset::whole_body_problem(body::apply_marker_set(body::mmm_body_model(1000), inferred.set),
                                      markerset::marker_extent_mm(recording), inferred.height_mm);
    if (!not_a_body->empty()) return inferred;
  }
  if (out.empty()) {
    inferred.set.name = std::filesystem::path(input).stem().string() + "_markerset";
    return inferred;
  }
  inferred.set.name = std::filesystem::path(out).stem().string();
  write_marker_set_file(out, inferred.set);
  return inferred;
}

/// Whether the best bundled set is good enough for these labels: it names at least as many of
/// them as the tracker needs to start (8). Not a fraction of the labels: Vicon files carry dozens
/// of virtual points (PELO, LTIO, ...) beside the markers.
inline bool bundled_set_fits(const std::vector<std::string>& labels, const body::MarkerSet& set) {
  return body::map_marker_set(labels, set).markers_used() >= track::TrackerOptions{}.min_markers_to_start;
}

/// The recording's labels that `set` does not name and that may be markers (not empty, not a
/// model output or joint centre by name): worth reading the recording to place them.
inline bool labels_beyond_set(const std::vector<std::string>& labels, const body::MarkerSet& set) {
  const body::MarkerMapping mapping = body::map_marker_set(labels, set);
  for (const std::string& label : mapping.ignored_labels)
    if (!label.empty() && !body::non_marker_reason(label, labels)) return true;
  return false;
}

/// `choice` completed for the recording at `input`: the labels its set does not name placed on
/// the segments they ride on (markerset::complete_marker_set), the combined set written to
/// `completed_path` (unless empty) when any was placed; the choice's source says so.
inline void complete_choice(const std::string& input, MarkerSetChoice& choice,
                            const std::string& completed_path) {
  const MarkerSequence recording = read_recording_to_infer(input);
  const markerset::MarkerSetInferenceOptions options = inference_options();
  markerset::CompletedMarkerSet completed;
  try {
    completed = markerset::complete_marker_set(recording, choice.set,
                                               cached_sample_set(46, kInferenceSamples), options);
  } catch (const std::invalid_argument& e) {
    throw UserError(input + ": " + e.what());
  }
  choice.inferred = completed.inferred;
  choice.left_out = completed.left_out;
  if (completed.inferred.empty()) return;
  completed.set.name = choice.set.name + "+inferred";
  if (!completed_path.empty()) write_marker_set_file(completed_path, completed.set);
  choice.set = completed.set;
  choice.source += "; with " + std::to_string(completed.inferred.size()) +
                   " marker(s) it does not name placed by their motion (label segment confidence:";
  for (const markerset::CompletedMarker& m : completed.inferred)
    choice.source +=
        " " + m.label + " " + m.segment + " " + std::to_string(std::lround(100 * m.confidence)) + " %";
  choice.source += completed_path.empty() ? ")" : "), written to " + completed_path;
  for (const std::string& note : completed.cluster_notes) choice.source += "; " + note;
}

/// choose_marker_set_for, completed with the labels the chosen set does not name (complete_choice);
/// when neither option names a set and no bundled set fits the labels, a set inferred from the
/// recording itself, written to `inferred_path` (unless empty), refused where it does not look like a whole
/// body unless `force`, with a sentence that ends in `remedy` (the front end's way to give a set or
/// force it); the choice's source says what was done. A subject file is used as it is.
inline MarkerSetChoice choose_or_infer_marker_set(const std::string& input,
                                                  const std::vector<std::string>& labels,
                                                  const std::string& markerset, const std::string& subject,
                                                  const std::string& inferred_path, bool force,
                                                  const std::string& remedy) {
  if (!subject.empty()) return choose_marker_set_for(labels, markerset, subject);
  const auto completed = [&](MarkerSetChoice choice) {
    // Only a file can be read again (not a live source, HOST:PORT): there the labels stay ignored.
    if (labels_beyond_set(labels, choice.set) && std::filesystem::is_regular_file(input)) {
      complete_choice(input, choice, inferred_path);
      return choice;
    }
    // Nothing to place: the labels the set does not name are no markers by name; say which.
    for (const std::string& label : body::map_marker_set(labels, choice.set).ignored_labels)
      if (const auto reason = body::non_marker_reason(label, labels))
        choice.left_out.push_back({label, *reason});
    return choice;
  };
  if (!markerset.empty()) return completed(choose_marker_set_for(labels, markerset, subject));
  std::vector<body::MarkerSet> sets;
  for (const std::string& name : bundled_marker_set_names()) sets.push_back(resolve_marker_set(name));
  const int best = body::choose_marker_set(labels, sets);
  if (best >= 0 && bundled_set_fits(labels, sets[static_cast<std::size_t>(best)]))
    return completed(choose_marker_set_for(labels, markerset, subject));
  const std::string bundled_problem =
      best < 0 ? std::string("none of the recording's labels belongs to a bundled marker set")
               : "no bundled marker set names 8 of the recording's labels (best: " +
                     sets[static_cast<std::size_t>(best)].name + ")";
  markerset::InferredMarkerSet inferred;
  std::string not_a_body;
  try {
    inferred = infer_marker_set_file(input, inferred_path, -1, force ? nullptr : &not_a_body);
  } catch (const UserError& e) {
    // The inference's sentence ends in "give a marker set (--markerset)"; say first why it ran.
    std::string why = e.what();
    if (why.rfind(input + ": ", 0) == 0) why = why.substr(input.size() + 2);
    throw UserError(input + ": " + bundled_problem + ", and " + why);
  }
  if (!not_a_body.empty())
    throw UserError(input + ": " + bundled_problem + ", and in the set inferred from its motion " +
                    not_a_body + "; nothing is tracked (" + remedy + ")");
  MarkerSetChoice choice;
  choice.set = inferred.set;
  choice.source =
      "inferred from the recording, as no bundled set names enough of its labels (best: " +
      (best < 0
           ? std::string("none")
           : sets[static_cast<std::size_t>(best)].name + " with " +
                 std::to_string(
                     body::map_marker_set(labels, sets[static_cast<std::size_t>(best)]).markers_used())) +
      ")" + (inferred_path.empty() ? std::string() : "; written to " + inferred_path) + "; " +
      inferred.notes.front() + "; confidence per segment:";
  for (const markerset::InferredSegment& s : inferred.segments)
    choice.source += " " + s.segment + " " + std::to_string(std::lround(100 * s.confidence)) + " %";
  return choice;
}

}  // namespace s2kf::app
