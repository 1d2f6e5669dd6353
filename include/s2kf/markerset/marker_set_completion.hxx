/// @file
/// The definitions of <s2kf/markerset/marker_set_completion.hpp>: inline where the library is used
/// header-only, compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/markerset/marker_set_completion.hpp>
#include <s2kf/markerset/marker_set_inference.hxx>

namespace s2kf::markerset {

S2KF_INLINE CompletedMarkerSet complete_marker_set(const MarkerSequence& recording,
                                                   const body::MarkerSet& known, const SampleSet& samples,
                                                   const MarkerSetInferenceOptions& options) {
  CompletedMarkerSet result;
  result.set = known;
  const body::MarkerMapping mapping = body::map_marker_set(recording.labels, known);
  result.known_markers = mapping.markers_used();
  std::vector<bool> is_known(recording.labels.size(), false);
  for (int p : mapping.point_of_marker)
    if (p >= 0) is_known[static_cast<std::size_t>(p)] = true;

  // The labels to place: named by no entry, seen, and not named as something other than a marker.
  std::vector<int> candidates, known_points;
  for (std::size_t p = 0; p < recording.labels.size(); ++p) {
    const std::string& label = recording.labels[p];
    const bool seen = recording.visible.row(static_cast<Eigen::Index>(p)).any();
    if (is_known[p]) {
      if (seen) known_points.push_back(static_cast<int>(p));
      continue;
    }
    if (label.empty()) continue;
    if (const auto reason = body::non_marker_reason(label, recording.labels))
      result.left_out.push_back({label, *reason});
    else if (!seen)
      result.left_out.push_back({label, "never seen"});
    else
      candidates.push_back(static_cast<int>(p));
  }
  if (candidates.empty()) return result;
  const auto leave_all_out = [&](const std::string& why) {
    for (int p : candidates) result.left_out.push_back({recording.labels[static_cast<std::size_t>(p)], why});
    result.notes.push_back("the labels the set does not name were not placed: " + why);
    return result;
  };

  std::vector<int> all = known_points;
  all.insert(all.end(), candidates.begin(), candidates.end());
  detail::InferenceContext c{recording, samples, options};
  std::vector<detail::FramedFit> shortlist;
  std::vector<int> far;
  std::string excluded_note;
  try {
    c.points = detail::inference_points(recording, options, &all);
    detail::find_clusters(c);
    detail::choose_template_frames(c);
    c.candidates = detail::template_points(c.base, options.known_sets);
    // The known set's own markers are places on the body too.
    for (const body::Marker& marker : body::apply_marker_set(c.base, known).markers)
      detail::add_template_point(c.candidates, marker);
    shortlist = detail::shortlist_template_fits(c, true);
    excluded_note = detail::leave_out_far_points(c, shortlist, known_points, &far);
  } catch (const std::invalid_argument& e) {
    return leave_all_out(e.what());
  }
  for (int p : far)
    result.left_out.push_back({c.label(p), "far (over " + std::to_string(std::lround(detail::kTemplateCap)) +
                                               " mm) from the body's surface in the template fit: a "
                                               "virtual point, no marker on the skin"});

  // The known markers where the set puts them (1000 mm), fixed through the rounds; the others
  // placed from the template, then (on segments the known markers ride on) by their tracked motion.
  const body::BodyModel wearing = body::apply_marker_set(c.base, known);
  std::vector<bool> fixed(c.points.size(), false);
  std::vector<int> model_marker(c.points.size(), -1);
  for (std::size_t m = 0; m < mapping.point_of_marker.size(); ++m)
    for (std::size_t i = 0; i < c.points.size(); ++i)
      if (c.points[i] == mapping.point_of_marker[m]) fixed[i] = true, model_marker[i] = static_cast<int>(m);
  // Clusters (LTBA-LTBD) go as a unit to the segment whose motion explains all their markers.
  const std::vector<detail::MarkerCluster> clusters = detail::label_clusters(c, fixed);
  std::vector<detail::Attempt> attempts(shortlist.size());
  parallel_for(static_cast<int>(shortlist.size()), options.threads, [&](int k) {
    detail::Attempt& a = attempts[static_cast<std::size_t>(k)];
    a = detail::initial_assignment(c, shortlist[static_cast<std::size_t>(k)], shortlist.size(),
                                   excluded_note);
    for (std::size_t i = 0; i < c.points.size(); ++i)
      if (fixed[i]) {
        const body::Marker& marker = wearing.markers[static_cast<std::size_t>(model_marker[i])];
        a.frame_of[i] = marker.frame;
        a.set.entries[i].frame = body::marker_set_frame_name(c.base, marker.frame);
        a.set.entries[i].offset = marker.offset;
      }
    detail::reassignment_rounds(c, a, fixed, clusters);
  });
  detail::Attempt kept;
  for (detail::Attempt& a : attempts)
    if (a.spread_rms_mm < kept.spread_rms_mm) kept = std::move(a);
  result.notes = kept.notes;
  result.cluster_notes = kept.cluster_notes;

  const std::vector<detail::PlacedMarker> placed = detail::marker_confidence(c, kept);
  const double to_reference = known.reference_height_mm / 1000.0;
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    if (fixed[i]) continue;
    const std::string segment = body::segment_of_frame(c.base, kept.frame_of[i]);
    if (!(placed[i].spread_mm <= options.max_spread_mm)) {
      std::ostringstream s;
      s << "rides rigidly on no segment (spread " << std::lround(placed[i].spread_mm) << " mm on its best, "
        << segment << ")";
      result.left_out.push_back({c.label(c.points[i]), s.str()});
      continue;
    }
    body::MarkerSetEntry entry = kept.set.entries[i];
    entry.offset *= to_reference;
    result.set.entries.push_back(entry);
    result.inferred.push_back({entry.label, segment, entry.frame, placed[i].spread_mm, placed[i].confidence});
  }
  std::ostringstream s;
  s << result.inferred.size() << " marker(s) the set " << known.name
    << " does not name were placed by their motion (" << kept.rounds << " round(s) of tracking); "
    << result.left_out.size() << " label(s) left out";
  result.notes.insert(result.notes.begin(), s.str());
  if (!result.inferred.empty()) {
    std::ostringstream description;
    description << (known.description.empty() ? "" : known.description + " ")
                << "Completed by s2kf with markers inferred from the recording's motion (label, segment, "
                   "confidence):";
    for (const CompletedMarker& m : result.inferred)
      description << " " << m.label << " " << m.segment << " " << std::lround(100 * m.confidence) << " %;";
    description << " check their frames and correct them by hand where the confidence is low.";
    result.set.description = description.str();
  }
  return result;
}

}  // namespace s2kf::markerset
