/// @file
/// The definitions of <s2kf/calibration/static_stretch.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/calibration/static_stretch.hpp>

namespace s2kf::calibration {
S2KF_INLINE std::optional<StaticStretch> find_static_stretch(FrameSource& source,
                                                             const std::vector<bool>& considered,
                                                             const StaticStretchOptions& options) {
  const double rate = source.rate_hz();
  if (!(rate > 0)) throw std::invalid_argument("a static stretch needs a positive frame rate");
  const auto points = static_cast<Eigen::Index>(source.labels().size());
  const std::int64_t block = std::max<std::int64_t>(2, std::llround(rate / 2));
  const std::int64_t blocks = source.frame_count() / block;
  const auto counts = [&](Eigen::Index p) {
    return considered.empty() || considered[static_cast<std::size_t>(p)];
  };
  Eigen::Index considered_points = 0;
  for (Eigen::Index p = 0; p < points; ++p) considered_points += counts(p);
  if (considered_points < 3) return std::nullopt;

  // Per block: each point's mean where it is well seen (NaN otherwise), and whether it is still.
  std::vector<Eigen::Matrix3Xd> means;
  std::vector<char> still;
  MarkerFrame frame;
  Eigen::Matrix3Xd sum(3, points), first_position(3, points);
  Eigen::VectorXi seen(points);
  std::vector<Eigen::Matrix3Xd> positions(static_cast<std::size_t>(block));
  std::vector<Eigen::Array<bool, Eigen::Dynamic, 1>> visible(static_cast<std::size_t>(block));
  for (std::int64_t b = 0; b < blocks; ++b) {
    sum.setZero();
    seen.setZero();
    for (std::int64_t k = 0; k < block; ++k) {
      if (!source.read(b * block + k, frame))
        throw std::invalid_argument("a frame of the recording could not be read");
      positions[static_cast<std::size_t>(k)] = frame.positions;
      visible[static_cast<std::size_t>(k)] = frame.visible;
      for (Eigen::Index p = 0; p < points; ++p)
        if (frame.visible(p) && frame.positions.col(p).allFinite())
          sum.col(p) += frame.positions.col(p), ++seen(p);
    }
    Eigen::Matrix3Xd mean = Eigen::Matrix3Xd::Constant(3, points, std::nan(""));
    Eigen::Index well_seen = 0;
    bool block_still = true;
    for (Eigen::Index p = 0; p < points; ++p) {
      if (!counts(p) || seen(p) < options.visible_share * static_cast<double>(block)) continue;
      ++well_seen;
      mean.col(p) = sum.col(p) / seen(p);
      for (std::int64_t k = 0; k < block && block_still; ++k)
        if (visible[static_cast<std::size_t>(k)](p) &&
            (positions[static_cast<std::size_t>(k)].col(p) - mean.col(p)).norm() > options.block_tolerance_mm)
          block_still = false;
    }
    means.push_back(mean);
    still.push_back(block_still &&
                    well_seen >= options.visible_share * static_cast<double>(considered_points));
  }

  // The longest run of still blocks whose means stay near the run's first block's.
  const auto max_blocks =
      static_cast<std::int64_t>(std::floor(options.max_seconds * rate / static_cast<double>(block)));
  std::optional<StaticStretch> best;
  for (std::int64_t start = 0; start < blocks; ++start) {
    if (!still[static_cast<std::size_t>(start)]) continue;
    if (start > 0 && still[static_cast<std::size_t>(start - 1)] && best &&
        best->first <= (start - 1) * block && (start - 1) * block < best->first + best->count)
      continue;  // inside a run already measured
    double largest = 0;
    std::int64_t end = start + 1;
    for (; end < blocks && end - start < max_blocks && still[static_cast<std::size_t>(end)]; ++end) {
      double farthest = 0;
      const Eigen::Matrix3Xd& a = means[static_cast<std::size_t>(start)];
      const Eigen::Matrix3Xd& c = means[static_cast<std::size_t>(end)];
      for (Eigen::Index p = 0; p < points; ++p)
        if (a.col(p).allFinite() && c.col(p).allFinite())
          farthest = std::max(farthest, (a.col(p) - c.col(p)).norm());
      if (farthest > options.stretch_tolerance_mm) break;
      largest = std::max(largest, farthest);
    }
    const std::int64_t count = (end - start) * block;
    if (static_cast<double>(count) < options.min_seconds * rate) continue;
    if (!best || count > best->count) best = StaticStretch{start * block, count, largest};
  }
  return best;
}

}  // namespace s2kf::calibration
