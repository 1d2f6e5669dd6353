// The error against the time a segment's markers have been hidden: bins counted by hand and RMS
// values in closed form on a motion whose error is known exactly.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/evaluation/hidden_time_error.hpp>
#include <s2kf/io/motion_files.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace {

using namespace s2kf;

constexpr double kRate = 10;  // Hz: frame k of a hidden stretch has been hidden k / 10 s
constexpr Eigen::Index kFrames = 60;

io::MotionTable still_motion(const body::BodyModel& model) {
  io::MotionTable motion;
  motion.joint_names = model.joint_names();
  motion.values = Eigen::MatrixXd::Zero(kFrames, 6 + model.joint_count());
  for (Eigen::Index k = 0; k < kFrames; ++k) {
    motion.frame.push_back(k);
    motion.time.push_back(static_cast<double>(k) / kRate);
  }
  return motion;
}

struct Fixture {
  body::BodyModel model = body::mmm_body_model(1750);
  body::MarkerMapping mapping;  // point p is model marker p
  Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic> visible;
  int segment_frame = -1;            // the segment whose markers are hidden
  std::vector<int> segment_markers;  // its markers
  int segments = 0;                  // segments (frames) carrying markers

  Fixture() {
    for (int m = 0; m < model.marker_count(); ++m) mapping.point_of_marker.push_back(m);
    visible.setConstant(model.marker_count(), kFrames, true);
    segment_frame = model.markers.front().frame;
    std::vector<int> frames;
    for (int m = 0; m < model.marker_count(); ++m) {
      const int f = model.markers[static_cast<std::size_t>(m)].frame;
      if (f == segment_frame) segment_markers.push_back(m);
      if (std::find(frames.begin(), frames.end(), f) == frames.end()) frames.push_back(f);
    }
    segments = static_cast<int>(frames.size());
  }
};

const evaluation::SegmentHiddenTimeError& segment(const evaluation::HiddenTimeError& e,
                                                  const std::string& name) {
  for (const auto& s : e.segments)
    if (s.segment == name) return s;
  throw std::runtime_error("no segment " + name);
}

TEST(HiddenTimeError, BinsFramesByTheTimeHiddenAndGivesTheirRms) {
  Fixture s;
  ASSERT_GE(s.segment_markers.size(), 2u);
  // One of the segment's markers hidden in frames 10-29: 20 frames, hidden 0.1 ... 2.0 s.
  for (Eigen::Index k = 10; k < 30; ++k) s.visible(s.segment_markers.front(), k) = false;
  const io::MotionTable truth = still_motion(s.model);
  io::MotionTable estimate = truth;
  // The root turned by 0.1 rad in frames 20-29 (hidden 1.1 ... 2.0 s): every segment is 0.1 rad off there.
  const double error = 0.1;
  for (Eigen::Index k = 20; k < 30; ++k) estimate.values(k, 3) = error;
  const evaluation::HiddenTimeError e =
      evaluation::hidden_time_error(s.model, estimate, truth, s.visible, s.mapping, kRate, 0);
  ASSERT_EQ(static_cast<int>(e.segments.size()), s.segments);
  const auto& hidden = segment(e, s.model.frame_name(s.segment_frame));
  EXPECT_EQ(hidden.markers, static_cast<int>(s.segment_markers.size()));
  // Edges 0.1, 0.25, 0.5, 1, 2 s: hidden k frames = k / 10 s falls in [0], (0, 0.1], (0.1, 0.25], ...
  const std::vector<long> frames = {40, 1, 1, 3, 5, 10, 0};
  ASSERT_EQ(hidden.bins.size(), frames.size());
  for (std::size_t b = 0; b < frames.size(); ++b) EXPECT_EQ(hidden.bins[b].frames, frames[b]) << "bin " << b;
  const double degrees = error * kDegreesPerRadian;
  EXPECT_NEAR(hidden.bins[5].rms_deg, degrees, 1e-9);  // (1, 2] s: all ten frames 0.1 rad off
  EXPECT_NEAR(hidden.bins[0].rms_deg, 0, 1e-9);
  EXPECT_NEAR(hidden.bins[4].rms_deg, 0, 1e-9);
  EXPECT_TRUE(std::isnan(hidden.bins[6].rms_deg));
  EXPECT_EQ(hidden.bins[5].lower_s, 1.0);
  EXPECT_EQ(hidden.bins[5].upper_s, 2.0);
  EXPECT_TRUE(std::isinf(hidden.bins[6].upper_s));
  // Over all segments: the others never hidden, 0.1 rad off in 10 of their 60 frames.
  const long others = s.segments - 1;
  EXPECT_EQ(e.all[0].frames, others * kFrames + 40);
  EXPECT_NEAR(
      e.all[0].rms_deg,
      degrees * std::sqrt(static_cast<double>(others * 10) / static_cast<double>(others * kFrames + 40)),
      1e-9);
  EXPECT_NEAR(e.all[5].rms_deg, degrees, 1e-9);
}

TEST(HiddenTimeError, LeavesOutTheWarmUpAndUntrackedFramesButCountsTheirHiddenTime) {
  Fixture s;
  for (Eigen::Index k = 0; k < 30; ++k)
    for (int m : s.segment_markers) s.visible(m, k) = false;
  const io::MotionTable truth = still_motion(s.model);
  io::MotionTable estimate = truth;
  estimate.values.row(25).setConstant(NAN);  // not tracked
  const evaluation::HiddenTimeError e =
      evaluation::hidden_time_error(s.model, estimate, truth, s.visible, s.mapping, kRate, 20);
  const auto& hidden = segment(e, s.model.frame_name(s.segment_frame));
  // Frames 20-29 (hidden 2.1 ... 3.0 s) land beyond 2 s, less the untracked frame 25; 30-59 are visible.
  EXPECT_EQ(hidden.bins[6].frames, 9);
  EXPECT_EQ(hidden.bins[0].frames, 30);
  long total = 0;
  for (const auto& bin : hidden.bins) total += bin.frames;
  EXPECT_EQ(total, 39);
}

TEST(HiddenTimeError, RejectsInputsThatDoNotFit) {
  Fixture s;
  const io::MotionTable truth = still_motion(s.model);
  body::MarkerMapping short_mapping = s.mapping;
  short_mapping.point_of_marker.pop_back();
  EXPECT_THROW(evaluation::hidden_time_error(s.model, truth, truth, s.visible, short_mapping, kRate, 0),
               std::invalid_argument);
  EXPECT_THROW(
      evaluation::hidden_time_error(s.model, truth, truth, s.visible.topRows(3), s.mapping, kRate, 0),
      std::invalid_argument);
  EXPECT_THROW(evaluation::hidden_time_error(s.model, truth, truth, s.visible, s.mapping, 0, 0),
               std::invalid_argument);
  EXPECT_THROW(
      evaluation::hidden_time_error(s.model, truth, truth, s.visible, s.mapping, kRate, 0, {0.5, 0.2}),
      std::invalid_argument);
  io::MotionTable other = truth;
  other.joint_names.back() = "XX";
  EXPECT_THROW(evaluation::hidden_time_error(s.model, other, truth, s.visible, s.mapping, kRate, 0),
               std::invalid_argument);
}

}  // namespace
