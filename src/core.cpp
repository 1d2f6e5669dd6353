// The compiled copy of the definitions in s2kf/core/ (core/compilation_mode.hpp).
#include <s2kf/core/lcd_distance.hxx>
#include <s2kf/core/lcd_sample_set.hxx>
#include <s2kf/core/marginal_update.hxx>
#include <s2kf/core/sample_set.hxx>
#include <s2kf/core/smart_sampling_kalman_filter.hxx>
