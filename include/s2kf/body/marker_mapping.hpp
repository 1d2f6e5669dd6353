/// @file
/// Mapping the point labels of a recording to the markers of a body model, by name.
#pragma once

#include <s2kf/body/label_text.hpp>

#include <algorithm>
#include <cctype>
#include <string>
#include <vector>

namespace s2kf::body {

/// Which recording point feeds which model marker. Recording labels the model does not know are
/// listed in `ignored_labels`; model markers without a recording point are never observed.
struct MarkerMapping {
  /// For every model marker, the index of its point in the recording, or -1.
  std::vector<int> point_of_marker;
  /// Recording labels that matched no model marker (after removing a "Subject:" prefix).
  std::vector<std::string> ignored_labels;
  /// What was done to match labels beyond their exact names (case, spelling, a subject prefix),
  /// one sentence each, for the summary.
  std::vector<std::string> label_notes;

  int markers_used() const {
    return static_cast<int>(
        std::count_if(point_of_marker.begin(), point_of_marker.end(), [](int p) { return p >= 0; }));
  }
};

/// Matches labels to marker names exactly first, then case-insensitively. When two recording
/// points carry the same marker name, the first one is used and the second is reported ignored.
inline MarkerMapping map_markers(const std::vector<std::string>& recording_labels,
                                 const std::vector<std::string>& model_marker_names) {
  MarkerMapping mapping;
  mapping.point_of_marker.assign(model_marker_names.size(), -1);
  for (std::size_t point = 0; point < recording_labels.size(); ++point) {
    const std::string name = strip_subject_prefix(recording_labels[point]);
    int marker = -1;
    for (std::size_t m = 0; m < model_marker_names.size() && marker < 0; ++m)
      if (model_marker_names[m] == name) marker = static_cast<int>(m);
    for (std::size_t m = 0; m < model_marker_names.size() && marker < 0; ++m)
      if (same_name_ignoring_case(model_marker_names[m], name)) marker = static_cast<int>(m);
    if (marker < 0 || mapping.point_of_marker[marker] >= 0) {
      mapping.ignored_labels.push_back(recording_labels[point]);
      continue;
    }
    mapping.point_of_marker[marker] = static_cast<int>(point);
  }
  return mapping;
}

}  // namespace s2kf::body
