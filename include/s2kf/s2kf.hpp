/// @file
/// Umbrella header: every public header of s2kf (the estimation core, the body model, marker data
/// and files, the simulator, the tracking pipeline). Include single headers to compile less.
#pragma once

#include <s2kf/core/bordered_cholesky.hpp>
#include <s2kf/core/box_muller.hpp>
#include <s2kf/core/chi_square.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/core/error.hpp>
#include <s2kf/core/exponential_integral.hpp>
#include <s2kf/core/gaussian.hpp>
#include <s2kf/core/instruction_set.hpp>
#include <s2kf/core/lcd_distance.hpp>
#include <s2kf/core/lcd_sample_set.hpp>
#include <s2kf/core/marginal_update.hpp>
#include <s2kf/core/parallel_for.hpp>
#include <s2kf/core/product_tiles.hpp>
#include <s2kf/core/rts_smoother.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/bounded_joints.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/label_text.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/marker_measurement_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/marker_set_labels.hpp>
#include <s2kf/body/marker_set_mapping.hpp>
#include <s2kf/body/non_marker_points.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/body/pose_columns.hpp>
#include <s2kf/body/reference_poses.hpp>
#include <s2kf/body/segment_inertia.hpp>
#include <s2kf/body/vector_sincos.hpp>

#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/bvh.hpp>
#include <s2kf/io/c3d_error.hpp>
#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/c3d_writer.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/io/mmm_motion.hpp>
#include <s2kf/io/motion_derivatives.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/io/motion_stream_writer.hpp>
#include <s2kf/io/number_text.hpp>
#include <s2kf/io/opensim_model.hpp>
#include <s2kf/io/sample_cache.hpp>
#include <s2kf/io/trc_file.hpp>

#include <s2kf/live/live_feed.hpp>
#include <s2kf/live/live_frame_source.hpp>
#include <s2kf/live/packet_channel.hpp>
#include <s2kf/live/qtm_client.hpp>
#include <s2kf/live/qtm_protocol.hpp>
#include <s2kf/live/qtm_server.hpp>
#include <s2kf/live/udp_sender.hpp>
#include <s2kf/sim/keyframe_motion.hpp>
#include <s2kf/sim/monotone_cubic.hpp>
#include <s2kf/sim/occlusion.hpp>
#include <s2kf/sim/random.hpp>
#include <s2kf/sim/random_sweep.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/soft_tissue.hpp>
#include <s2kf/sim/subject.hpp>

#include <s2kf/geometry/nearest_point_tree.hpp>
#include <s2kf/geometry/rigid_fit.hpp>

#include <s2kf/track/gradient_baseline.hpp>
#include <s2kf/track/quantile_histogram.hpp>
#include <s2kf/track/segment_observation.hpp>
#include <s2kf/track/stage_times.hpp>
#include <s2kf/track/state_chart.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracker_options.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/tracking_run.hpp>
#include <s2kf/track/tracking_smoother.hpp>

#include <s2kf/calibration/calibration_check.hpp>
#include <s2kf/calibration/height_estimate.hpp>
#include <s2kf/calibration/static_stretch.hpp>
#include <s2kf/calibration/static_trial_markers.hpp>
#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/calibration/subject_information.hpp>

#include <s2kf/pipeline/session.hpp>

#include <s2kf/markerset/body_coverage.hpp>
#include <s2kf/markerset/marker_set_completion.hpp>
#include <s2kf/markerset/marker_set_inference.hpp>
#include <s2kf/markerset/rigid_clusters.hpp>
#include <s2kf/markerset/segment_rigidity.hpp>

#include <s2kf/evaluation/evaluation.hpp>
#include <s2kf/evaluation/hidden_time_error.hpp>
#include <s2kf/evaluation/identifiable_subject_reference.hpp>
#include <s2kf/evaluation/true_subject_reference.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
