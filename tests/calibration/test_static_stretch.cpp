// The static stretch inside a recording: found where every marker stands still for a second or
// more, at its place and length; a pause shorter than a second, a slow drift and a marker that
// alone keeps moving are no static trial; points not considered do not decide.
#include <s2kf/calibration/static_stretch.hpp>
#include <s2kf/io/frame_source.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using namespace s2kf;

/// 10 points at 100 Hz for `frames` frames: still (1 mm noise) in [still_from, still_to), moving
/// 300 mm/s elsewhere.
MarkerSequence recording(long frames, long still_from, long still_to) {
  MarkerSequence s;
  s.rate_hz = 100;
  for (int p = 0; p < 10; ++p) s.labels.push_back("P" + std::to_string(p));
  s.resize(frames);
  std::mt19937 random(3);
  std::normal_distribution<double> noise(0, 1.0);
  for (long f = 0; f < frames; ++f) {
    const long moving = f < still_from ? f - still_from : (f >= still_to ? f - still_to : 0);
    Eigen::Matrix3Xd points(3, 10);
    for (int p = 0; p < 10; ++p)
      points.col(p) = Eigen::Vector3d(100.0 * p + 3.0 * static_cast<double>(moving), 50.0 * p, 1000) +
                      Eigen::Vector3d(noise(random), noise(random), noise(random));
    s.set_frame(f, points, Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(10, true));
  }
  return s;
}

TEST(StaticStretch, FindsTheStillSecondsAtTheStart) {
  const MarkerSequence s = recording(600, 0, 250);
  SequenceFrameSource source(s);
  const auto stretch = calibration::find_static_stretch(source, {});
  ASSERT_TRUE(stretch.has_value());
  EXPECT_EQ(stretch->first, 0);
  EXPECT_EQ(stretch->count, 250);  // whole half-second blocks: 5 of them
  EXPECT_LT(stretch->largest_motion_mm, 2.0);
}

TEST(StaticStretch, FindsTheLongestStillStretchAndCapsIt) {
  const MarkerSequence s = recording(1200, 300, 1000);  // 7 s still in the middle
  SequenceFrameSource source(s);
  const auto stretch = calibration::find_static_stretch(source, {});
  ASSERT_TRUE(stretch.has_value());
  EXPECT_GE(stretch->first, 300);
  EXPECT_EQ(stretch->count, 400);  // at most 4 s
  EXPECT_LE(stretch->first + stretch->count, 1000);
}

TEST(StaticStretch, APauseShorterThanASecondIsNone) {
  const MarkerSequence s = recording(600, 200, 290);
  SequenceFrameSource source(s);
  EXPECT_FALSE(calibration::find_static_stretch(source, {}).has_value());
}

TEST(StaticStretch, OneMovingMarkerOrASlowDriftIsNoStaticTrial) {
  MarkerSequence s = recording(600, 0, 600);
  for (long f = 0; f < 600; ++f) s.frame(f).col(4).x() += 100 * std::sin(0.2 * static_cast<double>(f));
  SequenceFrameSource source(s);
  EXPECT_FALSE(calibration::find_static_stretch(source, {}).has_value());
  // Not considered (an unlabelled point), it does not decide.
  std::vector<bool> considered(10, true);
  considered[4] = false;
  ASSERT_TRUE(calibration::find_static_stretch(source, considered).has_value());
  // A drift of 40 mm/s: each half second is still (10 mm from its mean), but only 1.5 s of them
  // stay within 50 mm of the first.
  MarkerSequence drift = recording(600, 0, 600);
  for (long f = 0; f < 600; ++f) drift.frame(f).row(0).array() += 0.4 * static_cast<double>(f);
  SequenceFrameSource drifting(drift);
  const auto stretch = calibration::find_static_stretch(drifting, {});
  ASSERT_TRUE(stretch.has_value());
  EXPECT_EQ(stretch->count, 150);
}

}  // namespace
