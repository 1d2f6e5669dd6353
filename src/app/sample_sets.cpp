// The program's one use of the sample cache (see tracker_samples.hpp).
#include <s2kf/app/sample_sets.hpp>

#include <s2kf/io/sample_cache.hpp>

namespace s2kf::app {

SampleSet cached_sample_set(int dimension, int count) { return lcd_sample_set(dimension, count).set; }

}  // namespace s2kf::app
