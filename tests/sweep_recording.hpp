/// @file
/// A simulated subject moving through a random sweep of its joints: the recording several
/// calibration tests start from.
#pragma once

#include <s2kf/sim/random_sweep.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

#include <cstdint>

namespace s2kf::test_support {

/// `frames` frames at 100 Hz of `subject` sweeping its joints for `duration_s` seconds; `seed`
/// draws the sweep and the recording's noise.
inline sim::Recording sweep_recording(const sim::Subject& subject, std::uint64_t seed, Eigen::Index frames,
                                      double duration_s) {
  sim::RandomSweepOptions sweep;
  sweep.duration_s = duration_s;
  const sim::KeyframeMotion motion = sim::random_sweep_motion(seed, subject.lower, subject.upper, sweep);
  sim::RecordingOptions options;
  options.frame_rate = 100;
  options.frames = frames;
  return sim::simulate_recording(motion, subject, options, seed);
}

}  // namespace s2kf::test_support
