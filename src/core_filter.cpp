// The compiled copy of the filter's definitions in s2kf/core/ (core/compilation_mode.hpp); the
// rest of the core compiles in core_sample_sets.cpp, so that neither unit takes 1.5 GB or a minute.
#include <s2kf/core/smart_sampling_kalman_filter.hxx>
