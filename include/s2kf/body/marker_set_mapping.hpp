/// @file
/// Mapping a recording's labels to the markers of a marker set (labels and their aliases), and
/// choosing, among several sets, the one that fits a recording best.
#pragma once

#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/marker_set_labels.hpp>
#include <s2kf/core/compilation_mode.hpp>

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

}  // namespace s2kf::body

#if !defined(S2KF_COMPILED)
#include <s2kf/body/marker_set_mapping.hxx>
#endif
