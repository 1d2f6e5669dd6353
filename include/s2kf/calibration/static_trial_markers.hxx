/// @file
/// The definitions of <s2kf/calibration/static_trial_markers.hpp>: inline where the library is used
/// header-only, compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/calibration/static_trial_markers.hpp>

namespace s2kf::calibration {
namespace detail {

/// The median distance between points a and b over the frames showing both; NaN when none does.
S2KF_INLINE double median_distance(const MarkerSequence& frames, int a, int b) {
  std::vector<double> distances;
  for (Eigen::Index f = 0; f < frames.frame_count(); ++f) {
    if (!frames.visible(a, f) || !frames.visible(b, f)) continue;
    const double d =
        (frames.positions.col(f).segment<3>(3 * a) - frames.positions.col(f).segment<3>(3 * b)).norm();
    if (std::isfinite(d)) distances.push_back(d);
  }
  if (distances.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto middle = distances.begin() + static_cast<std::ptrdiff_t>(distances.size() / 2);
  std::nth_element(distances.begin(), middle, distances.end());
  return *middle;
}

}  // namespace detail

S2KF_INLINE std::vector<MovedMarker> markers_moved_between_trials(
    const body::BodyModel& model, const body::MarkerMapping& static_mapping,
    const MarkerSequence& static_trial, const body::MarkerMapping& recording_mapping,
    const MarkerSequence& recording, const std::vector<bool>& named, double tolerance_mm) {
  const auto point = [](const body::MarkerMapping& mapping, const MarkerSequence& frames, int marker) {
    const auto m = static_cast<std::size_t>(marker);
    const int p = m < mapping.point_of_marker.size() ? mapping.point_of_marker[m] : -1;
    return p < frames.point_count() ? p : -1;
  };
  const auto shown = [](int p, const MarkerSequence& frames) {
    return p >= 0 && frames.visible.row(p).any();
  };
  const auto is_named = [&](int m) {
    return static_cast<std::size_t>(m) < named.size() && named[static_cast<std::size_t>(m)];
  };
  // Per pair of markers on one frame seen in both trials, not both named: how much their distance differs.
  std::map<std::pair<int, int>, double> mismatch;
  for (int a = 0; a < model.marker_count(); ++a)
    for (int b = a + 1; b < model.marker_count(); ++b) {
      if ((is_named(a) && is_named(b)) || model.markers[static_cast<std::size_t>(a)].frame !=
                                              model.markers[static_cast<std::size_t>(b)].frame)
        continue;
      const int sa = point(static_mapping, static_trial, a), sb = point(static_mapping, static_trial, b);
      const int ra = point(recording_mapping, recording, a), rb = point(recording_mapping, recording, b);
      if (sa < 0 || sb < 0 || ra < 0 || rb < 0) continue;
      const double d =
          detail::median_distance(static_trial, sa, sb) - detail::median_distance(recording, ra, rb);
      if (std::isfinite(d)) mismatch[{a, b}] = std::abs(d);
    }
  std::vector<MovedMarker> moved;
  std::vector<bool> out(static_cast<std::size_t>(model.marker_count()), false), judged(out.size(), false);
  const auto active = [&](const std::pair<int, int>& pair) {
    return !out[static_cast<std::size_t>(pair.first)] && !out[static_cast<std::size_t>(pair.second)];
  };
  // Per marker over its pairs with markers still in: count, disagreeing count, sum of squares.
  std::vector<int> pairs, disagreeing;
  std::vector<double> sum;
  const auto tally = [&]() {
    pairs.assign(out.size(), 0);
    disagreeing.assign(out.size(), 0);
    sum.assign(out.size(), 0.0);
    for (const auto& [pair, e] : mismatch) {
      if (!active(pair)) continue;
      for (const int m : {pair.first, pair.second}) {
        const auto i = static_cast<std::size_t>(m);
        if (is_named(m)) continue;
        sum[i] += e * e;
        ++pairs[i];
        if (e > tolerance_mm) ++disagreeing[i];
      }
    }
  };
  const auto rms = [&](std::size_t m) { return std::sqrt(sum[m] / std::max(pairs[m], 1)); };
  const auto leave_out = [&](std::size_t m, double mismatch_mm) {
    out[m] = true;
    moved.push_back({static_cast<int>(m), mismatch_mm});
  };
  // A marker with two or more named markers on its frame: judged against them alone, by the median
  // (one of them moved does not condemn it).
  std::vector<std::vector<double>> to_named(out.size());
  for (const auto& [pair, e] : mismatch)
    if (is_named(pair.first) != is_named(pair.second))
      to_named[static_cast<std::size_t>(is_named(pair.first) ? pair.second : pair.first)].push_back(e);
  for (std::size_t m = 0; m < out.size(); ++m) {
    std::vector<double>& e = to_named[m];
    if (e.size() < 2) continue;
    judged[m] = true;
    std::sort(e.begin(), e.end());
    if (const double median = e[(e.size() - 1) / 2]; median > tolerance_mm) leave_out(m, median);
  }
  // The others against every marker on their frame: the one at odds with the most out first.
  for (;;) {
    tally();
    std::size_t worst = out.size();
    for (std::size_t m = 0; m < out.size(); ++m)
      if (!judged[m] && disagreeing[m] > 0 &&
          (worst == out.size() || disagreeing[m] > disagreeing[worst] ||
           (disagreeing[m] == disagreeing[worst] && rms(m) > rms(worst))))
        worst = m;
    if (worst == out.size()) break;
    leave_out(worst, rms(worst));
  }
  // Confirmed only by two markers that agree: one distance matches by chance too often.
  for (bool changed = true; changed;) {
    changed = false;
    tally();
    for (int m = 0; m < model.marker_count(); ++m) {
      const auto i = static_cast<std::size_t>(m);
      if (is_named(m) || out[i] || judged[i] || pairs[i] - disagreeing[i] >= 2 ||
          !shown(point(static_mapping, static_trial, m), static_trial) ||
          !shown(point(recording_mapping, recording, m), recording))
        continue;
      leave_out(i, pairs[i] > 0 ? rms(i) : std::numeric_limits<double>::quiet_NaN());
      changed = true;
    }
  }
  return moved;
}

}  // namespace s2kf::calibration
