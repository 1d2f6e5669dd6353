/// @file
/// The definitions of <s2kf/evaluation/hidden_time_error.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/evaluation/hidden_time_error.hpp>

namespace s2kf::evaluation {

S2KF_INLINE HiddenTimeError hidden_time_error(
    const body::BodyModel& model, const io::MotionTable& estimate, const io::MotionTable& truth,
    const Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>& visible, const body::MarkerMapping& mapping,
    double rate_hz, long warmup, const std::vector<double>& edges) {
  if (estimate.joint_names != model.joint_names() || truth.joint_names != model.joint_names())
    throw std::invalid_argument("hidden_time_error: joint columns differ from the body model's");
  if (mapping.point_of_marker.size() != static_cast<std::size_t>(model.marker_count()))
    throw std::invalid_argument("hidden_time_error: the marker mapping does not fit the body model");
  if (!(rate_hz > 0)) throw std::invalid_argument("hidden_time_error: the frame rate must be positive");
  for (std::size_t b = 0; b < edges.size(); ++b)
    if (!(edges[b] > (b ? edges[b - 1] : 0.0)) || !std::isfinite(edges[b]))
      throw std::invalid_argument("hidden_time_error: the bin edges must be positive, finite and increasing");
  const Eigen::Index rows =
      std::min({estimate.frames(), truth.frames(), static_cast<Eigen::Index>(visible.cols())});
  // Each segment's mapped points.
  std::vector<int> frames_of_segment;
  std::vector<std::vector<int>> points;
  for (int m = 0; m < model.marker_count(); ++m) {
    const int point = mapping.point_of_marker[static_cast<std::size_t>(m)];
    if (point < 0) continue;
    if (point >= visible.rows())
      throw std::invalid_argument("hidden_time_error: a mapped point has no visibility row");
    const int frame = model.markers[static_cast<std::size_t>(m)].frame;
    const auto found = std::find(frames_of_segment.begin(), frames_of_segment.end(), frame);
    if (found == frames_of_segment.end()) {
      frames_of_segment.push_back(frame);
      points.push_back({point});
    } else {
      points[static_cast<std::size_t>(found - frames_of_segment.begin())].push_back(point);
    }
  }
  const std::size_t bins = edges.size() + 2;  // [0, 0], (0, e0], ..., (e_last, inf)
  const auto bin_of = [&](double seconds) {
    if (seconds <= 0) return std::size_t{0};
    std::size_t b = 1;
    while (b - 1 < edges.size() && seconds > edges[b - 1]) ++b;
    return b;
  };
  std::vector<std::vector<double>> sum(frames_of_segment.size(), std::vector<double>(bins, 0.0));
  std::vector<std::vector<long>> count(frames_of_segment.size(), std::vector<long>(bins, 0));
  std::vector<long> hidden_for(frames_of_segment.size(), 0);
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (std::size_t s = 0; s < frames_of_segment.size(); ++s) {
      bool all_visible = true;
      for (int point : points[s]) all_visible = all_visible && visible(point, r);
      hidden_for[s] = all_visible ? 0 : hidden_for[s] + 1;
    }
    if (r < warmup || !io::is_tracked_row(estimate.values.row(r).transpose()) ||
        !truth.values.row(r).allFinite())
      continue;
    const body::FrameTransforms fe = body::joint_frames(model, pose_of_row(estimate, r));
    const body::FrameTransforms ft = body::joint_frames(model, pose_of_row(truth, r));
    for (std::size_t s = 0; s < frames_of_segment.size(); ++s) {
      const auto f = static_cast<std::size_t>(frames_of_segment[s]);
      const double angle = Eigen::AngleAxisd(fe.rotations[f].transpose() * ft.rotations[f]).angle();
      if (!std::isfinite(angle)) continue;  // beyond a joint that is not observed
      const std::size_t b = bin_of(static_cast<double>(hidden_for[s]) / rate_hz);
      sum[s][b] += angle * angle;
      ++count[s][b];
    }
  }
  const auto make_bins = [&](const std::vector<double>& sq, const std::vector<long>& n) {
    std::vector<HiddenTimeBin> out(bins);
    for (std::size_t b = 0; b < bins; ++b) {
      out[b].lower_s = b == 0 ? 0.0 : (b == 1 ? 0.0 : edges[b - 2]);
      out[b].upper_s = b == 0 ? 0.0 : (b - 1 < edges.size() ? edges[b - 1] : INFINITY);
      out[b].frames = n[b];
      out[b].rms_deg = n[b] ? std::sqrt(sq[b] / static_cast<double>(n[b])) * kDegreesPerRadian : NAN;
    }
    return out;
  };
  HiddenTimeError result;
  std::vector<double> all_sum(bins, 0.0);
  std::vector<long> all_count(bins, 0);
  for (std::size_t s = 0; s < frames_of_segment.size(); ++s) {
    result.segments.push_back({model.frame_name(frames_of_segment[s]), static_cast<int>(points[s].size()),
                               make_bins(sum[s], count[s])});
    for (std::size_t b = 0; b < bins; ++b) all_sum[b] += sum[s][b], all_count[b] += count[s][b];
  }
  result.all = make_bins(all_sum, all_count);
  return result;
}

}  // namespace s2kf::evaluation
