/// @file
/// Marker data over time: labelled 3D points per frame with their visibility. The one in-memory
/// form of a recording, whatever it came from (a C3D file, the simulator, a live system), and what
/// the tracker, the calibration and the evaluation read.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf {

/// Which of a frame's points are seen.
using FrameVisibility = Eigen::Array<bool, Eigen::Dynamic, 1>;

/// One frame of marker positions.
struct MarkerFrame {
  std::int64_t index = 0;  ///< 0-based among the recording's frames
  /// Column p is point p in mm; NaN where the point is missing.
  Eigen::Matrix3Xd positions;
  /// visible(p) is false for a missing point. A missing point never has stale coordinates.
  FrameVisibility visible;
};

/// Every frame of a recording in memory: 24 bytes plus one flag per point and frame.
struct MarkerSequence {
  std::vector<std::string> labels;  ///< one per point, as the source names it
  double rate_hz = 0;               ///< frames per second
  /// 3P x F: rows 3p..3p+2 of column f are point p of frame f in mm, NaN when missing.
  Eigen::MatrixXd positions;
  /// P x F: false where a point is missing.
  Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic> visible;

  Eigen::Index frame_count() const { return positions.cols(); }
  Eigen::Index point_count() const { return visible.rows(); }
  double time_s(Eigen::Index f) const { return static_cast<double>(f) / rate_hz; }
  /// Frame f as a 3 x P view in mm.
  Eigen::Map<const Eigen::Matrix3Xd> frame(Eigen::Index f) const {
    return Eigen::Map<const Eigen::Matrix3Xd>(positions.col(f).data(), 3, point_count());
  }
  Eigen::Map<Eigen::Matrix3Xd> frame(Eigen::Index f) {
    return Eigen::Map<Eigen::Matrix3Xd>(positions.col(f).data(), 3, point_count());
  }
  /// Frame f copied into `frame` (which keeps its storage when the size is unchanged).
  void read_frame(Eigen::Index f, MarkerFrame& out) const {
    out.index = f;
    out.positions = frame(f);
    out.visible = visible.col(f);
  }
  /// Sizes the sequence for `frames` frames of `labels.size()` points, all missing.
  void resize(Eigen::Index frames) {
    const auto points = static_cast<Eigen::Index>(labels.size());
    positions.setConstant(3 * points, frames, std::numeric_limits<double>::quiet_NaN());
    visible.setConstant(points, frames, false);
  }
  /// Sets frame f; non-finite coordinates count as missing and are stored as NaN.
  void set_frame(Eigen::Index f, const Eigen::Matrix3Xd& points, const FrameVisibility& seen) {
    if (points.cols() != point_count() || seen.size() != point_count())
      throw std::invalid_argument("MarkerSequence::set_frame: one column and flag per point is needed");
    for (Eigen::Index p = 0; p < point_count(); ++p) {
      const bool ok = seen(p) && points.col(p).allFinite();
      visible(p, f) = ok;
      frame(f).col(p) = ok ? Eigen::Vector3d(points.col(p))
                           : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    }
  }
  /// Frames [first, first + count) as a sequence of their own (frame numbers restart at 0).
  MarkerSequence frames(Eigen::Index first, Eigen::Index count) const {
    MarkerSequence part;
    part.labels = labels;
    part.rate_hz = rate_hz;
    part.positions = positions.middleCols(first, count);
    part.visible = visible.middleCols(first, count);
    return part;
  }
  /// The frames of `more` (the same points) appended after these; an empty sequence becomes `more`.
  void append_frames(const MarkerSequence& more) {
    if (frame_count() == 0) {
      *this = more;
      return;
    }
    if (more.point_count() != point_count())
      throw std::invalid_argument("MarkerSequence::append_frames: both sequences must have the same points");
    positions.conservativeResize(Eigen::NoChange, frame_count() + more.frame_count());
    positions.rightCols(more.frame_count()) = more.positions;
    visible.conservativeResize(Eigen::NoChange, positions.cols());
    visible.rightCols(more.frame_count()) = more.visible;
  }
};

}  // namespace s2kf
