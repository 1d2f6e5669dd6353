/// @file
/// Where the tracking pipeline reads marker frames from: a file read as it goes (C3D), a sequence
/// in memory, or anything a user plugs in. Random access, because the pipeline reads a few spread
/// frames (height estimate, calibration) before it streams them all.
#pragma once

#include <s2kf/io/marker_sequence.hpp>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// One label per point, in the order of a frame's columns.
  virtual const std::vector<std::string>& labels() const = 0;
  virtual double rate_hz() const = 0;
  virtual std::int64_t frame_count() const = 0;
  /// Frame `index` (0-based) into `frame`; false when there is no such frame. Reading the frames in
  /// order is what every source must make cheap.
  virtual bool read(std::int64_t index, MarkerFrame& frame) = 0;
};

/// A MarkerSequence as a frame source (the sequence must outlive it).
class SequenceFrameSource : public FrameSource {
 public:
  explicit SequenceFrameSource(const MarkerSequence& sequence) : sequence_(sequence) {}
  const std::vector<std::string>& labels() const override { return sequence_.labels; }
  double rate_hz() const override { return sequence_.rate_hz; }
  std::int64_t frame_count() const override { return sequence_.frame_count(); }
  bool read(std::int64_t index, MarkerFrame& frame) override {
    if (index < 0 || index >= sequence_.frame_count()) return false;
    sequence_.read_frame(index, frame);
    return true;
  }

 private:
  const MarkerSequence& sequence_;
};

/// Frames [first, first + count) of a source read into memory (fewer at the end of the source).
inline MarkerSequence read_frames(FrameSource& source, std::int64_t first, std::int64_t count) {
  MarkerSequence sequence;
  sequence.labels = source.labels();
  sequence.rate_hz = source.rate_hz();
  const std::int64_t end = std::min<std::int64_t>(source.frame_count(), first + count);
  sequence.resize(std::max<std::int64_t>(0, end - first));
  MarkerFrame frame;
  for (std::int64_t f = first; f < end; ++f) {
    if (!source.read(f, frame)) throw std::runtime_error("frame " + std::to_string(f) + " could not be read");
    sequence.set_frame(f - first, frame.positions, frame.visible);
  }
  return sequence;
}

}  // namespace s2kf
