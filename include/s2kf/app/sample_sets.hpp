/// @file
/// The S2KF sample sets the program's commands track with, from the on-disk cache (computed and
/// stored on first use). Declared here and defined once in tracker_samples.cpp, so only that file
/// compiles the sample-set optimiser.
#pragma once

#include <s2kf/core/sample_set.hpp>

namespace s2kf::app {

/// The cached LCD sample set of `count` samples for `dimension` dimensions.
SampleSet cached_sample_set(int dimension, int count);

}  // namespace s2kf::app
