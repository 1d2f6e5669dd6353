/// @file
/// Inferring a marker set for a recording whose labels no known set names: which segment of the
/// body model each marker rides on, and where. See docs/real-data.md ("Inferring a marker set").
///
/// 1. Rigid clusters (rigid_clusters.hpp): a recording in which nothing moves against anything
///    else cannot be told apart and is refused.
/// 2. A template fit in each of several frames spread over the recording (those showing the most
///    markers): the model at its zero pose, arms down to out sideways, scaled and turned about the
///    recording's vertical, its surface given by the markers of the known sets (the places where
///    labs put markers); where the zero pose fits poorly (a subject mid-motion), the pose is
///    refined. Shortlisted: the frames whose facing direction wins clearly, those where the zero
///    pose fitted first; the one whose set then tracks most rigidly (step 4) is kept. No such
///    frame, and the recording is refused. Each marker takes the frame of the nearest template
///    point, its offset where the fitted pose puts it; points far from every template point
///    (virtual points) are left out.
/// 3. The topology check (segment_rigidity.hpp): a marker whose distances to its segment's other
///    markers vary by centimetres, but stay constant to another segment's, moves there.
/// 4. Rounds of tracking and reassignment: the recording is tracked with the current set; each
///    marker then moves to the model frame in which its position stays most constant over the
///    tracked frames, at its mean position there (a fit over many frames). Rounds end when no
///    marker moves.
/// 5. Confidence: a marker's is 1 - (its spread on its segment) / (its spread on the best other
///    segment), lowered where the distances to its segment's markers are not clearly steadier
///    than to another's, and halved for a marker alone on its segment; a segment's is the mean
///    over its markers. A fit that leaves the markers far from rigid on any segment is refused.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/label_text.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/markerset/rigid_clusters.hpp>
#include <s2kf/markerset/segment_rigidity.hpp>
#include <s2kf/track/tracker_options.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::markerset {

struct MarkerSetInferenceOptions {
  /// The recording's vertical: 0, 1 or 2 for x, y or z up; -1: the axis along which the markers
  /// of the candidate template frames spread furthest (a subject is taller than wide).
  int up_axis = -1;
  /// Candidate frames for the template fit, spread evenly over the frames that show the most
  /// markers: a recording need not start standing.
  int template_frames = 8;
  /// Of those, the ones whose facing direction wins most clearly are tried through the rounds of
  /// tracking, at most this many; the one whose markers then ride most rigidly is kept.
  int template_attempts = 3;
  /// The pose is refined (hips, knees, shoulders, elbows, trunk) only where the zero pose with the
  /// arms turned out leaves an RMS residual above this: a subject mid-motion, not one standing.
  double refine_pose_above_rms_mm = 30.0;
  track::TrackerOptions tracker;  ///< for the rounds of tracking (fewer samples are enough)
  long frames = 600;              ///< frames tracked per round at most, from the start
  long skip_frames = 20;          ///< tracked frames left out at the start of each round (convergence)
  int max_rounds = 4;
  /// Threads for the template fits of the candidate frames and the shortlisted attempts' rounds
  /// (each on its own; the result does not depend on the count).
  int threads = 1;
  RigidClusterOptions clusters;
  SegmentRigidityOptions rigidity;  ///< the topology check that repairs the template's assignment
  /// Refusals: the facing direction of the template fit must beat every direction more than 60
  /// degrees away by this factor of cost; the markers' RMS spread on their segments must stay
  /// below max_spread_mm.
  double heading_margin = 1.1;
  double max_spread_mm = 30.0;
  /// A marker moves to another frame only where its spread is below this fraction of its spread
  /// on its current frame: a segment that barely moves against its neighbour in the recording
  /// (the lumbar spine against the pelvis in a walk) leaves its markers where the template put them.
  double move_ratio = 0.6;
  /// A marker whose spread on its frame stays below this rides on it well enough and stays: where a
  /// joint hardly moved in the recording (a wrist held straight), the neighbour fits as well and
  /// only the template can tell them apart. 15 mm: twice the simulated subjects' soft tissue.
  double rigid_spread_mm = 15.0;
  /// Known marker sets whose markers (besides the base model's own) describe the body surface for
  /// the template fit.
  std::vector<body::MarkerSet> known_sets;
};

/// How well one segment's markers were placed.
struct InferredSegment {
  std::string segment;
  int markers = 0;
  double spread_mm = 0;   ///< RMS over its markers of their spread on it over the tracked frames
  double confidence = 0;  ///< mean over its markers of 1 - spread on it / spread on the best other
};

struct InferredMarkerSet {
  body::MarkerSet set;  ///< explicit frames and offsets at 1000 mm, labels as recorded
  double height_mm = 0;
  int up_axis = 2;
  long template_frame = 0;
  int rounds = 0;
  RigidClusters clusters;
  std::vector<InferredSegment> segments;  ///< the segments that carry markers, in model order
  double spread_mm = 0;                   ///< RMS over all markers
  std::vector<std::string> notes;         ///< what was done, one sentence each
};

/// Infers a marker set for `recording` (labels as recorded; points with empty labels, model
/// outputs, are left out). Throws std::invalid_argument with one sentence when the recording
/// cannot be labelled unambiguously: too few markers or frames, one rigid cluster, no frame with a
/// clear facing direction, or markers that ride rigidly on no segment.
InferredMarkerSet infer_marker_set(const MarkerSequence& recording, const SampleSet& samples,
                                   const MarkerSetInferenceOptions& options = {});

}  // namespace s2kf::markerset

#if !defined(S2KF_COMPILED)
#include <s2kf/markerset/marker_set_inference.hxx>
#endif
