/// @file
/// Umbrella header: the estimation core of s2kf.
#pragma once

#include <s2kf/core/chi_square.hpp>
#include <s2kf/core/error.hpp>
#include <s2kf/core/gaussian.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>
