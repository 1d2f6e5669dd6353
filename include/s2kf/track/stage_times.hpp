/// @file
/// Where the time of tracking a recording goes: wall-clock seconds per stage of the pipeline (read,
/// marker set, height, calibration, tracking, smoothing, writing). prepare_session and run_session measure
/// what they do; the caller adds what happens outside them (opening the file, finishing the outputs).
#pragma once

#include <s2kf/io/frame_source.hpp>

#include <chrono>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::track {

struct StageTimes {
  double read = 0;         ///< opening the recording and reading its frames (for every stage)
  double marker_set = 0;   ///< choosing the marker set, completing or inferring it from the motion
  double height = 0;       ///< estimating the subject's height, its reads excluded
  double calibration = 0;  ///< calibrating the subject, its reads excluded
  double tracking = 0;     ///< the filter (or the baseline) on every frame
  double smoothing = 0;    ///< recording the posteriors and the backward pass (--smooth)
  double writing = 0;      ///< the output files

  double sum() const { return read + marker_set + height + calibration + tracking + smoothing + writing; }

  StageTimes& operator+=(const StageTimes& other) {
    read += other.read;
    marker_set += other.marker_set;
    height += other.height;
    calibration += other.calibration;
    tracking += other.tracking;
    smoothing += other.smoothing;
    writing += other.writing;
    return *this;
  }
};

inline StageTimes operator+(StageTimes a, const StageTimes& b) { return a += b; }

/// The stages' names and their seconds, in pipeline order.
inline std::vector<std::pair<std::string, double>> stage_list(const StageTimes& times) {
  return {{"read", times.read},         {"marker_set", times.marker_set},
          {"height", times.height},     {"calibration", times.calibration},
          {"tracking", times.tracking}, {"smoothing", times.smoothing},
          {"writing", times.writing}};
}

/// Seconds from `start` to now on the steady clock.
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// A frame source that forwards to another and adds the time its reads take to `seconds`: the read
/// stage, separated from the stages that read as they go (height estimate, calibration, tracking).
class TimedFrameSource : public FrameSource {
 public:
  TimedFrameSource(FrameSource& source, double& seconds) : source_(source), seconds_(seconds) {}
  const std::vector<std::string>& labels() const override { return source_.labels(); }
  double rate_hz() const override { return source_.rate_hz(); }
  std::int64_t frame_count() const override { return source_.frame_count(); }
  bool read(std::int64_t index, MarkerFrame& frame) override {
    const auto start = std::chrono::steady_clock::now();
    const bool found = source_.read(index, frame);
    seconds_ += seconds_since(start);
    return found;
  }

 private:
  FrameSource& source_;
  double& seconds_;
};

}  // namespace s2kf::track
