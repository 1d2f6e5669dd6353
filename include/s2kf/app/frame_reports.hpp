/// @file
/// The per-frame reports `s2kf track` writes beside the motion: PREFIX_markers.csv (the mean
/// marker distance and the visible markers of each frame) and PREFIX_segments.csv (each segment's
/// posterior standard deviation).
#pragma once

#include <s2kf/io/number_text.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/segment_observation.hpp>

#include <Eigen/Core>

#include <cmath>
#include <iomanip>
#include <limits>
#include <ostream>

namespace s2kf::app {

/// PREFIX_markers.csv: its header, and one line per frame.
inline void write_marker_report_header(std::ostream& out) {
  out << "frame,time,mean_marker_distance_mm,visible_markers\n";
}
inline void write_marker_report_row(std::ostream& out, const track::TrackedFrame& f) {
  out << std::setprecision(9) << f.frame << ",";
  io::write_general(out, f.time, 9);
  out << ",";
  if (std::isfinite(f.mean_marker_distance))
    io::write_general(out, f.mean_marker_distance, 9);
  else
    out << "nan";
  out << "," << f.visible_markers << "\n";
}

/// PREFIX_segments.csv: per segment, the filter's largest standard deviation of its angles this
/// frame (deg, segment_uncertainty_deg; "nan" where the frame was not filtered, e.g. rows replayed
/// after smoothing).
inline void write_segment_report_header(std::ostream& out, const track::SegmentObservation& segments) {
  out << "frame,time";
  for (const std::string& segment : segments.segments) out << "," << segment << "_sd_deg";
  out << "\n";
}
inline void write_segment_report_row(std::ostream& out, const pipeline::Session& session,
                                     const track::TrackedFrame& f) {
  Eigen::VectorXd sd = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(session.segments.segments.size()),
                                                 std::numeric_limits<double>::quiet_NaN());
  if (f.estimate && f.estimate->tracked)
    sd = track::segment_uncertainty_deg(session.model, session.segments, f.estimate->pose.joints,
                                        f.estimate->covariance);
  out << std::setprecision(6) << f.frame << ",";
  io::write_general(out, f.time, 6);
  for (Eigen::Index s = 0; s < sd.size(); ++s) {
    out << ",";
    if (std::isfinite(sd(s)))
      io::write_general(out, sd(s), 6);
    else
      out << "nan";
  }
  out << "\n";
}

}  // namespace s2kf::app
