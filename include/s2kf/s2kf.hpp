/// @file
/// Umbrella header: everything of s2kf (the estimation core, the body model, C3D and motion files,
/// the simulator and the tracker). Include single headers to compile less.
#pragma once

#include <s2kf/core/chi_square.hpp>
#include <s2kf/core/error.hpp>
#include <s2kf/core/gaussian.hpp>
#include <s2kf/core/lcd_distance.hpp>
#include <s2kf/core/lcd_sample_set.hpp>
#include <s2kf/core/sample_cache.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/bounded_joints.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_measurement_model.hpp>
#include <s2kf/body/pose.hpp>

#include <s2kf/io/bvh.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/c3d_writer.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/io/motion_stream_writer.hpp>

#include <s2kf/track/gradient_baseline.hpp>
#include <s2kf/track/height_estimate.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/tracking_run.hpp>
#include <s2kf/track/truth_metrics.hpp>
