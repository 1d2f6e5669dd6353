/// @file
/// Mapping a recording's labels to the markers of a marker set (labels and their aliases), and
/// choosing, among several sets, the one that fits a recording best.
#pragma once

#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/marker_set_labels.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/body/marker_mapping.hpp>

#include <string>
#include <vector>

namespace s2kf::body {

/// Like map_markers, for a model made by apply_marker_set(base, set) (markers in the set's
/// order): labels are assigned to entries by assign_labels (exact names and aliases, then ignoring
/// case, spelling and a subject prefix), and what that did beyond exact names is in label_notes.
MarkerMapping map_marker_set(const std::vector<std::string>& recording_labels, const body::MarkerSet& set);

/// Index of the set that fits the labels best: the one that finds the most of the recording's
/// markers, ties broken by the fraction of the set found (the smaller set that the recording fills:
/// a lower-body recording takes the lower-body set, not the full one it is half of), then by order.
/// -1 when no set matches any label.
int choose_marker_set(const std::vector<std::string>& recording_labels,
                      const std::vector<body::MarkerSet>& sets);

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

S2KF_INLINE MarkerMapping map_marker_set(const std::vector<std::string>& recording_labels,
                                         const body::MarkerSet& set) {
  const body::LabelAssignment assignment = body::assign_labels(recording_labels, set);
  MarkerMapping mapping;
  mapping.point_of_marker.assign(set.entries.size(), -1);
  for (std::size_t point = 0; point < recording_labels.size(); ++point) {
    const int entry = assignment.entry_of_label[point];
    if (entry < 0)
      mapping.ignored_labels.push_back(recording_labels[point]);
    else
      mapping.point_of_marker[static_cast<std::size_t>(entry)] = static_cast<int>(point);
  }
  mapping.label_notes = assignment.notes(recording_labels, set);
  return mapping;
}

S2KF_INLINE int choose_marker_set(const std::vector<std::string>& recording_labels,
                                  const std::vector<body::MarkerSet>& sets) {
  int best = -1;
  double best_score = 0;
  int best_used = 0;
  for (std::size_t s = 0; s < sets.size(); ++s) {
    const double score = body::marker_set_match(recording_labels, sets[s]);
    const int used = map_marker_set(recording_labels, sets[s]).markers_used();
    if (used > best_used || (used == best_used && used > 0 && score > best_score)) {
      best = static_cast<int>(s);
      best_score = score;
      best_used = used;
    }
  }
  return best;
}

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::body
