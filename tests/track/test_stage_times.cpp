// The stage timing of the pipeline (track/stage_times.hpp): a timed frame source forwards every
// frame unchanged and adds at least the time its reads took (a source that sleeps 2 ms per read),
// and stage times add up stage by stage.
#include <s2kf/track/stage_times.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

namespace s2kf {
namespace {

/// Three frames of two points; each read sleeps `delay`.
class SlowSource : public FrameSource {
 public:
  explicit SlowSource(std::chrono::milliseconds delay) : delay_(delay) {}
  const std::vector<std::string>& labels() const override { return labels_; }
  double rate_hz() const override { return 120; }
  std::int64_t frame_count() const override { return 3; }
  bool read(std::int64_t index, MarkerFrame& frame) override {
    std::this_thread::sleep_for(delay_);
    if (index < 0 || index >= 3) return false;
    frame.index = index;
    frame.positions = Eigen::Matrix3Xd::Constant(3, 2, static_cast<double>(index));
    frame.visible = FrameVisibility::Constant(2, index != 1);
    return true;
  }

 private:
  std::chrono::milliseconds delay_;
  std::vector<std::string> labels_{"LASI", "RASI"};
};

TEST(StageTimes, ATimedSourceForwardsEveryFrameAndCountsTheTimeOfItsReads) {
  SlowSource slow(std::chrono::milliseconds(2));
  double seconds = 0.5;  // adds to what is there
  track::TimedFrameSource timed(slow, seconds);
  EXPECT_EQ(timed.labels(), slow.labels());
  EXPECT_EQ(timed.rate_hz(), 120);
  EXPECT_EQ(timed.frame_count(), 3);
  MarkerFrame frame;
  for (std::int64_t f = 0; f < 3; ++f) {
    ASSERT_TRUE(timed.read(f, frame));
    EXPECT_EQ(frame.index, f);
    EXPECT_EQ(frame.positions(2, 1), static_cast<double>(f));
    EXPECT_EQ(frame.visible(0), f != 1);
  }
  EXPECT_FALSE(timed.read(3, frame));
  EXPECT_GE(seconds, 0.5 + 4 * 0.002);                  // four reads of at least 2 ms each
  const MarkerSequence all = read_frames(timed, 0, 3);  // through the pipeline's own helper
  EXPECT_EQ(all.frame_count(), 3);
  EXPECT_GE(seconds, 0.5 + 7 * 0.002);
}

TEST(StageTimes, AddUpStageByStage) {
  const track::StageTimes a{1, 0.5, 2, 3, 4, 5, 6};
  const track::StageTimes b{0.5, 0.125, 0.25, 0, 2, 0, 1};
  const track::StageTimes sum = a + b;
  EXPECT_EQ(sum.read, 1.5);
  EXPECT_EQ(sum.marker_set, 0.625);
  EXPECT_EQ(sum.height, 2.25);
  EXPECT_EQ(sum.calibration, 3);
  EXPECT_EQ(sum.tracking, 6);
  EXPECT_EQ(sum.smoothing, 5);
  EXPECT_EQ(sum.writing, 7);
  EXPECT_EQ(sum.sum(), 21 + 3.75 + 0.625);
  const auto list = track::stage_list(sum);
  ASSERT_EQ(list.size(), 7u);
  const char* names[] = {"read", "marker_set", "height", "calibration", "tracking", "smoothing", "writing"};
  const double values[] = {1.5, 0.625, 2.25, 3, 6, 5, 7};
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(list[i].first, names[i]);
    EXPECT_EQ(list[i].second, values[i]);
  }
}

}  // namespace
}  // namespace s2kf
