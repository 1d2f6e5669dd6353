/// @file
/// The definitions of <s2kf/body/marker_set_mapping.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/body/marker_set_mapping.hpp>

namespace s2kf::body {

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

}  // namespace s2kf::body
