// The compiled copy of the definitions in s2kf/track/ (core/compilation_mode.hpp).
#include <s2kf/track/gradient_baseline.hxx>
#include <s2kf/track/segment_observation.hxx>
#include <s2kf/track/state_chart.hxx>
#include <s2kf/track/tracker.hxx>
#include <s2kf/track/tracker_options.hxx>
#include <s2kf/track/tracking_smoother.hxx>
