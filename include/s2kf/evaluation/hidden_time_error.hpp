/// @file
/// How a segment's orientation error grows with the time its markers have been hidden: every
/// compared frame of every segment (a frame markers ride on) is put in a bin by how long, up to
/// that frame, the segment has not shown all of its markers, and the bins' RMS errors against the
/// truth are returned per segment and over all segments.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/io/motion_files.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::evaluation {

/// One bin: frames whose hidden time t (seconds) lies in (lower_s, upper_s]; the first bin,
/// [0, 0], holds the frames that show every marker of the segment.
struct HiddenTimeBin {
  double lower_s = 0, upper_s = 0;
  long frames = 0;     ///< segment frames in the bin
  double rms_deg = 0;  ///< NaN when empty
};

struct SegmentHiddenTimeError {
  std::string segment;  ///< the frame's name (as TruthComparison::segment_rms_deg)
  int markers = 0;      ///< markers of the segment that the recording maps
  std::vector<HiddenTimeBin> bins;
};

struct HiddenTimeError {
  std::vector<SegmentHiddenTimeError> segments;
  std::vector<HiddenTimeBin> all;  ///< every segment's frames together
};

/// The default bin edges (seconds) after the fully visible bin: up to 0.1 s, 0.25, 0.5, 1, 2,
/// and beyond.
inline std::vector<double> default_hidden_time_edges() { return {0.1, 0.25, 0.5, 1.0, 2.0}; }

/// The hidden time of segment frames from `warmup` on, binned. `visible` is the recording's
/// (points x frames) visibility that the tracker saw, `mapping` its points per model marker;
/// segments without a mapped marker are left out. A frame is compared when both motions have it
/// (finite, tracked) as in compare_with_truth. Throws std::invalid_argument when the motions'
/// joints are not the model's, the visibility does not fit or the edges do not increase.
HiddenTimeError hidden_time_error(const body::BodyModel& model, const io::MotionTable& estimate,
                                  const io::MotionTable& truth,
                                  const Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>& visible,
                                  const body::MarkerMapping& mapping, double rate_hz, long warmup,
                                  const std::vector<double>& edges = default_hidden_time_edges());

}  // namespace s2kf::evaluation

#if !defined(S2KF_COMPILED)
#include <s2kf/evaluation/hidden_time_error.hxx>
#endif
