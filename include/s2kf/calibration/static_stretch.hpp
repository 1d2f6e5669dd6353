/// @file
/// A static trial inside a recording: the longest stretch in which the subject stands still (every
/// well-seen marker within a few millimetres of where it was), which many sessions start or end
/// with. Whether the posture there is a reference pose is the static calibration's to say.
#pragma once

#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/frame_source.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <vector>

namespace s2kf::calibration {

struct StaticStretchOptions {
  double min_seconds = 1.0;  ///< shorter stillness is a pause, not a static trial
  double max_seconds = 4.0;  ///< enough for the calibration; the rest of a long stillness is left
  /// Within a half-second block every well-seen marker stays this close (mm) to its block mean, and
  /// every block of the stretch stays this close to the first block's means (the bundled static
  /// motion's sway, 1-3 degrees with the arms out in a T-pose, moves the hands by up to 40 mm).
  double block_tolerance_mm = 15.0;
  double stretch_tolerance_mm = 50.0;
  /// A marker is well seen in a block when visible in this share of its frames; a block counts
  /// when this share of the markers considered is well seen.
  double visible_share = 0.9;
};

struct StaticStretch {
  std::int64_t first = 0, count = 0;
  double largest_motion_mm = 0;  ///< the largest distance of a marker from the first block's mean
};

/// The longest stretch of `source` in which the subject stands still, from its first frame on
/// whole half-second blocks; `considered[p]` says whether point p counts (empty: all points), so
/// that unlabelled or unmapped points do not decide. None when no stretch lasts min_seconds.
std::optional<StaticStretch> find_static_stretch(FrameSource& source, const std::vector<bool>& considered,
                                                 const StaticStretchOptions& options = {});

}  // namespace s2kf::calibration

#if !defined(S2KF_COMPILED)
#include <s2kf/calibration/static_stretch.hxx>
#endif
