/// @file
/// A live stream as the pipeline's FrameSource: a first stretch held in memory (the session is
/// prepared on it: the height, the calibration), then every frame as it arrives, read in order.
/// Frame numbers the server skipped (or frames dropped while the tracker was busy) become frames
/// without markers, up to a bound, so that the filter's prediction spans the gap in time.
#pragma once

#include <s2kf/io/frame_source.hpp>
#include <s2kf/live/live_feed.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>

namespace s2kf::live {

struct LiveSourceOptions {
  std::int64_t max_frames = -1;  ///< end after this many frames (-1: no limit)
  double max_seconds = -1;       ///< end after this many seconds of stream time (-1: no limit)
  /// A gap in the frame numbers up to this long (seconds) is filled with frames without markers
  /// (the filter predicts across it); a longer one is crossed in one step.
  double max_gap_seconds = 1.0;
  /// Polled while waiting for a frame: true ends the stream (Ctrl-C).
  std::function<bool()> stop_requested;
};

class LiveFrameSource : public FrameSource {
 public:
  LiveFrameSource(LiveFeed& feed, LiveSourceOptions options) : feed_(feed), options_(std::move(options)) {
    labels_ = feed_.parameters().labels;
    max_fill_ = static_cast<std::int64_t>(std::floor(options_.max_gap_seconds * feed_.parameters().rate_hz));
  }

  const std::vector<std::string>& labels() const override { return labels_; }
  double rate_hz() const override { return feed_.parameters().rate_hz; }
  /// Frames delivered so far (a stream's length is not known in advance).
  std::int64_t frame_count() const override { return next_; }

  /// Holds the next `count` frames in memory (fewer when the stream ends first) and returns them:
  /// the stretch the session is prepared on; read() delivers them first. Until the consumer has
  /// caught up with the stream, the feed keeps up to `count` new frames (LiveFeed::keep_until_caught_up).
  const MarkerSequence& hold_first(std::int64_t count) {
    first_.labels = labels_;
    first_.rate_hz = rate_hz();
    MarkerFrame frame;
    std::vector<MarkerFrame> frames;
    holding_ = true;
    while (static_cast<std::int64_t>(frames.size()) < count && next_live(frame)) frames.push_back(frame);
    holding_ = false;
    feed_.keep_until_caught_up(static_cast<std::size_t>(std::max<std::int64_t>(0, count)));
    first_.resize(static_cast<std::int64_t>(frames.size()));
    for (std::size_t f = 0; f < frames.size(); ++f)
      first_.set_frame(static_cast<std::int64_t>(f), frames[f].positions, frames[f].visible);
    return first_;
  }

  /// Frames in order only: `index` must be the next one.
  bool read(std::int64_t index, MarkerFrame& frame) override {
    if (index != next_) return false;
    if (index < first_.frame_count()) {
      first_.read_frame(index, frame);
      frame.index = index;
      ++next_;
      return true;
    }
    if (!next_live(frame)) return false;
    frame.index = next_++;
    return true;
  }

  /// Frame numbers missing from the stream (server skips, frames dropped while busy, reconnects).
  long missing_frames() const { return missing_; }
  /// Frames without markers put in for missing ones.
  long filled_frames() const { return filled_; }
  /// The index and arrival time of the last frame that came from the stream (not a filled one).
  std::int64_t last_arrival_index() const { return last_arrival_index_; }
  std::chrono::steady_clock::time_point last_arrival() const { return last_arrival_; }
  /// True when the stream ended because stop_requested said so.
  bool stopped() const { return stopped_; }
  /// True when the stream ended at max_frames or max_seconds.
  bool limited() const { return limited_; }

 private:
  bool limit_reached() const {
    const std::int64_t delivered = delivered_;
    if (options_.max_frames >= 0 && delivered >= options_.max_frames) return true;
    if (options_.max_seconds >= 0 && static_cast<double>(delivered) >= options_.max_seconds * rate_hz())
      return true;
    return false;
  }

  bool next_live(MarkerFrame& frame) {
    if (limit_reached()) {
      limited_ = true;
      return false;
    }
    if (fill_ > 0) {
      --fill_;
      ++filled_;
      ++delivered_;
      frame.positions.setConstant(3, static_cast<Eigen::Index>(labels_.size()),
                                  std::numeric_limits<double>::quiet_NaN());
      frame.visible.setConstant(static_cast<Eigen::Index>(labels_.size()), false);
      return true;
    }
    if (held_) {
      held_ = false;
      return deliver(frame);
    }
    for (;;) {
      if (options_.stop_requested && options_.stop_requested()) {
        stopped_ = true;
        return false;
      }
      const LiveFeed::Next next = feed_.next(pending_, 100);
      if (next == LiveFeed::Next::ended) return false;
      if (next == LiveFeed::Next::timeout) continue;
      // A number at or before the last one (the server started again) continues the run.
      const std::int64_t gap = started_ && pending_.number > expected_ ? pending_.number - expected_ : 0;
      started_ = true;
      expected_ = static_cast<std::int64_t>(pending_.number) + 1;
      missing_ += gap;
      fill_ = std::min(gap, max_fill_);
      if (fill_ > 0) {
        held_ = true;
        return next_live(frame);
      }
      return deliver(frame);
    }
  }

  bool deliver(MarkerFrame& frame) {
    frame.positions = pending_.positions;
    frame.visible = pending_.visible;
    last_arrival_ = pending_.arrival;
    last_arrival_index_ = holding_ ? -1 : next_;
    ++delivered_;
    return true;
  }

  LiveFeed& feed_;
  LiveSourceOptions options_;
  std::vector<std::string> labels_;
  MarkerSequence first_;
  std::int64_t next_ = 0;
  std::int64_t delivered_ = 0;
  std::int64_t expected_ = 0;
  std::int64_t max_fill_ = 0;
  std::int64_t fill_ = 0;
  bool started_ = false;
  bool held_ = false;
  bool holding_ = false;
  bool stopped_ = false;
  bool limited_ = false;
  long missing_ = 0;
  long filled_ = 0;
  LiveFrame pending_;
  std::int64_t last_arrival_index_ = -1;
  std::chrono::steady_clock::time_point last_arrival_;
};

}  // namespace s2kf::live
