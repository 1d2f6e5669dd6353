// A run over frames (track/tracking_run.hpp) whose per-frame series are cut (a stream, s2kf live):
// the series keep only the first frames, and the summary numbers from the statistics of every frame
// agree with those of the same run kept whole: the converged frame for the histogram's median, the
// means to rounding, the time quantiles within the histogram's resolution. A tracker stands in that reports a
// given distance and time per frame.
#include <s2kf/track/tracking_run.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace s2kf::track {
namespace {

/// Reports distance[i] mm and seconds[i] s for the i-th frame; never a pose.
struct ScriptedTracker {
  std::vector<double> distance, seconds;
  std::size_t next = 0;
  FrameEstimate estimate;
  const FrameEstimate& process(const Eigen::Matrix3Xd&, const FrameVisibility&) {
    estimate.mean_marker_distance = distance[next];
    estimate.seconds = seconds[next];
    ++next;
    return estimate;
  }
};

/// A filter's distance: 60 mm falling to about 8 mm over its first two seconds, then noise around
/// 8 mm with a frame now and then without markers (NaN); times around 0.5 ms.
ScriptedTracker converging_tracker(std::size_t frames, double rate_hz, unsigned seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0, 1);
  std::lognormal_distribution<double> time(std::log(0.5e-3), 0.3);
  ScriptedTracker t;
  for (std::size_t f = 0; f < frames; ++f) {
    const double seconds_in = static_cast<double>(f) / rate_hz;
    const double level = 8 + 52 * std::exp(-3 * seconds_in);
    t.distance.push_back(f % 97 == 50 ? std::nan("") : level + noise(random));
    t.seconds.push_back(time(random));
  }
  return t;
}

TrackingRun run_over(ScriptedTracker tracker, double rate_hz, long series_limit) {
  const std::size_t frames = tracker.distance.size();
  std::size_t read = 0;
  const auto next_frame = [&](MarkerFrame& frame) {
    if (read == frames) return false;
    frame.index = static_cast<std::int64_t>(read++);
    frame.positions = Eigen::Matrix3Xd::Zero(3, 1);
    frame.visible = FrameVisibility::Constant(1, true);
    return true;
  };
  return run_tracking(
      tracker, next_frame, rate_hz, {}, false, {}, [](const TrackedFrame&) {}, series_limit);
}

TEST(TrackingRun, ACutRunGivesTheSummaryOfTheWholeOne) {
  const double rate = 300;
  for (unsigned seed : {1u, 2u, 3u}) {
    const ScriptedTracker tracker = converging_tracker(20000, rate, seed);
    const TrackingRun whole = run_over(tracker, rate, -1);
    const TrackingRun cut = run_over(tracker, rate, 3000);
    ASSERT_TRUE(whole.complete_series());
    ASSERT_FALSE(cut.complete_series());
    EXPECT_EQ(whole.mean_marker_distance.size(), 20000u);
    EXPECT_EQ(cut.mean_marker_distance.size(), 3000u);  // memory: the first frames only
    EXPECT_EQ(cut.seconds.size(), 3000u);
    EXPECT_EQ(cut.frames, 20000);

    // The threshold is 1.5 times the median, from the histogram within its resolution: the frame
    // found is the one the whole series gives for that threshold, a frame or so from the exact one.
    const DistanceLevel exact = distance_level(whole, rate), kept = distance_level(cut, rate);
    const double median = cut.distance_statistics.quantile(0.5);
    EXPECT_NEAR(median, quantile(tracker.distance, 0.5), 0.005 * median);
    ASSERT_GT(exact.converged_frame, 0);
    EXPECT_EQ(kept.converged_frame,
              converged_frame_below(whole.mean_marker_distance, frames_per_second(rate), 1.5 * median));
    EXPECT_LE(std::abs(kept.converged_frame - exact.converged_frame), 3);
    const double level = mean_from(whole.mean_marker_distance, kept.converged_frame);
    EXPECT_NEAR(kept.level_mm, level, 1e-9 * level);  // exact but for the order of the sums
    EXPECT_NEAR(kept.overall_mm, exact.overall_mm, 1e-9 * exact.overall_mm);
    EXPECT_EQ(cut.seconds_statistics.sum(), whole.seconds_statistics.sum());
    for (double q : {0.5, 0.99}) {
      const double exact_seconds = seconds_quantile(whole, q);
      EXPECT_EQ(exact_seconds, quantile(tracker.seconds, q));  // the whole run's: a sort
      EXPECT_NEAR(seconds_quantile(cut, q), exact_seconds,
                  cut.seconds_statistics.resolution() * exact_seconds);
    }
  }
}

TEST(TrackingRun, ARunNoLongerThanItsCutKeepsExactNumbers) {
  const ScriptedTracker tracker = converging_tracker(1000, 100, 4);
  const TrackingRun cut = run_over(tracker, 100, 1000);
  EXPECT_TRUE(cut.complete_series());
  EXPECT_EQ(seconds_quantile(cut, 0.5), quantile(tracker.seconds, 0.5));
  EXPECT_EQ(distance_level(cut, 100).converged_frame,
            converged_frame(tracker.distance, frames_per_second(100)));
}

TEST(TrackingRun, NoConvergenceWithinTheKeptFramesIsNoConvergence) {
  // The distance falls only after the kept frames: the cut run cannot see where, and says so (-1,
  // no level) rather than guessing; the mean over every frame is still exact.
  ScriptedTracker tracker = converging_tracker(5000, 100, 5);
  for (std::size_t f = 0; f < 2000; ++f) tracker.distance[f] = 80 + static_cast<double>(f % 7);
  const TrackingRun whole = run_over(tracker, 100, -1), cut = run_over(tracker, 100, 1000);
  EXPECT_GE(distance_level(whole, 100).converged_frame, 1900);
  const DistanceLevel kept = distance_level(cut, 100);
  EXPECT_EQ(kept.converged_frame, -1);
  EXPECT_TRUE(std::isnan(kept.level_mm));
  EXPECT_NEAR(kept.overall_mm, distance_level(whole, 100).overall_mm, 1e-9 * kept.overall_mm);
}

}  // namespace
}  // namespace s2kf::track
