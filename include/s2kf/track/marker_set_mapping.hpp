/// @file
/// Mapping a recording's labels to the markers of a marker set (labels and their aliases), and
/// choosing, among several sets, the one that fits a recording best.
#pragma once

#include <s2kf/body/marker_set.hpp>
#include <s2kf/track/marker_mapping.hpp>

#include <string>
#include <vector>

namespace s2kf::track {

/// Like map_markers, for a model made by apply_marker_set(base, set) (markers in the set's
/// order): a label matches an entry by its label or an alias, exactly first, then ignoring case.
inline MarkerMapping map_marker_set(const std::vector<std::string>& recording_labels,
                                    const body::MarkerSet& set) {
  MarkerMapping mapping;
  mapping.point_of_marker.assign(set.entries.size(), -1);
  const auto find = [&set](const std::string& name, bool ignore_case) {
    const auto same = [&](const std::string& a) {
      return ignore_case ? same_name_ignoring_case(a, name) : a == name;
    };
    for (std::size_t m = 0; m < set.entries.size(); ++m) {
      if (same(set.entries[m].label)) return static_cast<int>(m);
      for (const std::string& alias : set.entries[m].aliases)
        if (same(alias)) return static_cast<int>(m);
    }
    return -1;
  };
  for (std::size_t point = 0; point < recording_labels.size(); ++point) {
    const std::string name = strip_subject_prefix(recording_labels[point]);
    int marker = name.empty() ? -1 : find(name, false);
    if (marker < 0 && !name.empty()) marker = find(name, true);
    if (marker < 0 || mapping.point_of_marker[static_cast<std::size_t>(marker)] >= 0) {
      mapping.ignored_labels.push_back(recording_labels[point]);
      continue;
    }
    mapping.point_of_marker[static_cast<std::size_t>(marker)] = static_cast<int>(point);
  }
  return mapping;
}

/// Index of the set that fits the labels best: the highest marker_set_match, ties broken by the
/// number of markers matched, then by order. -1 when no set matches any label.
inline int choose_marker_set(const std::vector<std::string>& recording_labels,
                             const std::vector<body::MarkerSet>& sets) {
  int best = -1;
  double best_score = 0;
  int best_used = 0;
  for (std::size_t s = 0; s < sets.size(); ++s) {
    const double score = body::marker_set_match(recording_labels, sets[s]);
    const int used = map_marker_set(recording_labels, sets[s]).markers_used();
    if (score > best_score || (score == best_score && score > 0 && used > best_used)) {
      best = static_cast<int>(s);
      best_score = score;
      best_used = used;
    }
  }
  return best;
}

}  // namespace s2kf::track
