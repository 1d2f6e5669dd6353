// MarkerSequence: frames appended after others, and a part taken back out, are the frames given.
#include <gtest/gtest.h>

#include <stdexcept>

#include "s2kf/io/marker_sequence.hpp"

namespace {

using s2kf::MarkerSequence;

/// A sequence of `frames` frames of two points whose coordinates count up from `start`; point 1 is
/// missing in odd frames.
MarkerSequence counting(Eigen::Index frames, double start) {
  MarkerSequence sequence;
  sequence.labels = {"A", "B"};
  sequence.rate_hz = 100;
  sequence.resize(frames);
  for (Eigen::Index f = 0; f < frames; ++f) {
    Eigen::Matrix3Xd points(3, 2);
    for (int i = 0; i < 6; ++i) points(i % 3, i / 3) = start + 6.0 * static_cast<double>(f) + i;
    s2kf::FrameVisibility seen(2);
    seen << true, f % 2 == 0;
    sequence.set_frame(f, points, seen);
  }
  return sequence;
}

TEST(MarkerSequence, AppendedFramesFollowTheFirstOnesAndComeBackOutAsTheyWere) {
  const MarkerSequence first = counting(3, 0), second = counting(2, 1000);
  MarkerSequence joined;
  joined.append_frames(first);  // an empty sequence becomes the first
  EXPECT_EQ(joined.labels, first.labels);
  EXPECT_EQ(joined.rate_hz, 100);
  joined.append_frames(second);
  ASSERT_EQ(joined.frame_count(), 5);
  // Each part, taken back out, has the frames it was made of: the seen points' coordinates, the
  // missing ones NaN.
  const auto same = [](const MarkerSequence& part, const MarkerSequence& original) {
    ASSERT_EQ(part.frame_count(), original.frame_count());
    EXPECT_TRUE((part.visible == original.visible).all());
    for (Eigen::Index f = 0; f < part.frame_count(); ++f)
      for (Eigen::Index p = 0; p < part.point_count(); ++p) {
        if (original.visible(p, f))
          EXPECT_EQ(part.frame(f).col(p), original.frame(f).col(p)) << "frame " << f << " point " << p;
        else
          EXPECT_TRUE(part.frame(f).col(p).hasNaN()) << "frame " << f << " point " << p;
      }
  };
  same(joined.frames(0, 3), first);
  same(joined.frames(3, 2), second);
  EXPECT_EQ(joined.frame(3)(0, 0), 1000.0);
  EXPECT_EQ(joined.frame(2)(0, 0), 12.0);
}

TEST(MarkerSequence, FramesOfOtherPointsAreNotAppended) {
  MarkerSequence joined = counting(2, 0);
  MarkerSequence other;
  other.labels = {"A"};
  other.resize(1);
  EXPECT_THROW(joined.append_frames(other), std::invalid_argument);
  EXPECT_EQ(joined.frame_count(), 2);
}

}  // namespace
