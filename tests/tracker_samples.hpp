/// @file
/// The sample sets the tests track with: the cached LCD set for the tracker's 46 dimensions,
/// computed once per sample count and process.
#pragma once

#include <s2kf/io/sample_cache.hpp>
#include <s2kf/track/tracker_options.hpp>

#include <map>

namespace s2kf::test {

inline const SampleSet& tracker_samples(int count = track::TrackerOptions{}.samples) {
  static std::map<int, SampleSet> sets;
  auto found = sets.find(count);
  if (found == sets.end()) found = sets.emplace(count, lcd_sample_set(46, count).set).first;
  return found->second;
}

inline const SampleSet& tracker_samples(const track::TrackerOptions& options) {
  return tracker_samples(options.samples);
}

}  // namespace s2kf::test
