/// @file
/// A known marker set completed by inference: the labels the set names are mapped as it says;
/// every other label that rides rigidly on a segment is placed there by the steps of the
/// marker-set inference (marker_set_inference.hpp), with the known markers fixed; labels that are
/// no markers (model outputs, joint centres, segment axes: body/non_marker_points.hpp), far from
/// the body or rigid on no segment are left out with a reason. For labs that mix sets: Plug-in
/// Gait on the trunk and arms with clusters on the legs, or a standard set with a few labels
/// renamed. See docs/marker-sets.md.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/marker_set_mapping.hpp>
#include <s2kf/body/non_marker_points.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/markerset/marker_set_inference.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::markerset {

/// A label the known set does not name, placed on a segment.
struct CompletedMarker {
  std::string label;
  std::string segment;    ///< "root", "LK", ...
  std::string frame;      ///< its frame in the marker-set file
  double spread_mm = 0;   ///< RMS spread of its position on that frame over the tracked frames
  double confidence = 0;  ///< as the inference's: 1 - spread there / spread on the best other segment
};

/// A label left out, and why (one clause).
struct LeftOutPoint {
  std::string label;
  std::string reason;
};

struct CompletedMarkerSet {
  body::MarkerSet set;    ///< the known set's entries, then the inferred markers (explicit frames)
  int known_markers = 0;  ///< markers of the known set the recording has
  std::vector<CompletedMarker> inferred;
  std::vector<LeftOutPoint> left_out;
  std::vector<std::string> notes;  ///< what was done, one sentence each
  /// Clusters placed by their name where their motion did not decide, or that their motion
  /// places only narrowly or beside a segment that carries no marker (one clause each).
  std::vector<std::string> cluster_notes;
};

/// `known` completed for `recording` (labels as recorded; empty labels, the reader's model
/// outputs, are skipped). A marker whose spread on its best segment exceeds
/// options.max_spread_mm is left out. Where the inference cannot place the other labels at all
/// (the template fit is refused), they are all left out with its sentence; the known set stays.
CompletedMarkerSet complete_marker_set(const MarkerSequence& recording, const body::MarkerSet& known,
                                       const SampleSet& samples,
                                       const MarkerSetInferenceOptions& options = {});

}  // namespace s2kf::markerset

#if !defined(S2KF_COMPILED)
#include <s2kf/markerset/marker_set_completion.hxx>
#endif
