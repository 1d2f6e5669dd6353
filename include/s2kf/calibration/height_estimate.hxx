/// @file
/// The definitions of <s2kf/calibration/height_estimate.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/calibration/height_estimate.hpp>

namespace s2kf::calibration {
S2KF_INLINE std::optional<HeightEstimate> estimate_height(FrameSource& source, const body::BodyModel& model,
                                                          const body::MarkerMapping& mapping,
                                                          std::int64_t max_frames) {
  HeightEstimator estimator(model, mapping);
  const std::int64_t frames = source.frame_count();
  const std::int64_t step = std::max<std::int64_t>(1, frames / max_frames);
  MarkerFrame frame;
  for (std::int64_t f = 0; f < frames; f += step) {
    if (!source.read(f, frame)) break;
    estimator.add_frame(frame.positions, frame.visible);
  }
  const std::optional<double> mm = estimator.height_mm();
  if (!mm) return std::nullopt;
  return HeightEstimate{*mm, estimator.pair_count()};
}

S2KF_INLINE void HeightEstimator::add_frame(const Eigen::Matrix3Xd& points,
                                            const Eigen::Array<bool, Eigen::Dynamic, 1>& visible) {
  for (const Pair& pair : pairs_) {
    const int pa = mapping_.point_of_marker[pair.a], pb = mapping_.point_of_marker[pair.b];
    if (pa >= points.cols() || pb >= points.cols() || !visible(pa) || !visible(pb)) continue;
    const double d = (points.col(pa) - points.col(pb)).norm();
    if (std::isfinite(d) && d > 0) ratios_.push_back(d / pair.model_distance);
  }
}

S2KF_INLINE std::optional<double> HeightEstimator::height_mm() const {
  if (ratios_.empty()) return std::nullopt;
  std::vector<double> sorted = ratios_;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  return height_ * sorted[sorted.size() / 2];
}

}  // namespace s2kf::calibration
