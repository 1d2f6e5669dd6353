// The per-frame gradient baseline, the evaluation library (both methods, the occlusion Monte
// Carlo, the sample sweep); the `s2kf evaluate` command's tests are in tests/cli/.
//
// Sizes are small on purpose (60 frames, L = 93, 2 runs): the suite also runs under sanitizers.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/evaluation/evaluation.hpp>
#include <s2kf/evaluation/true_subject_reference.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/sim/occlusion.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>
#include <s2kf/track/gradient_baseline.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/tracking_run.hpp>

#include <s2kf/app/motion_json.hpp>
#include "test_files.hpp"

#include "tracked_recording.hpp"
#include "tracker_samples.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>
#include "address_sanitizer.hpp"

namespace {

using namespace s2kf;
namespace fs = std::filesystem;
using namespace test_support;

constexpr double kDegrees = 180.0 / 3.14159265358979323846;

/// A handstand played on a subject exactly like the model (no segment scaling, placement, soft
/// tissue or noise): the markers are the model's markers at the truth.
sim::Recording exact_handstand(Eigen::Index frames, double height_mm) {
  const body::BodyModel reference = body::mmm_body_model(1000);
  const app::JointTable joints{reference.joint_names(), reference.lower_limits(), reference.upper_limits()};
  const sim::KeyframeMotion motion = app::load_motion_file(data_file("motions/handstand.json"), joints, 1);
  sim::SubjectOptions subject_options;
  subject_options.height_mm = height_mm;
  subject_options.segment_scale_sd = subject_options.placement_sd_mm = 0;
  subject_options.soft_tissue_mm = subject_options.noise_sd_mm = 0;
  const sim::Subject subject = sim::make_subject(reference, subject_options, 7);
  sim::RecordingOptions options;
  options.frames = frames;
  return sim::simulate_recording(motion, subject, options, 7);
}

io::MotionTable truth_table(const sim::Recording& recording, const body::BodyModel& model) {
  io::MotionTable truth;
  truth.joint_names = model.joint_names();
  truth.values.resize(recording.frames(), 6 + model.joint_count());
  for (Eigen::Index k = 0; k < recording.frames(); ++k) {
    const body::Pose& pose = recording.truth[static_cast<std::size_t>(k)];
    truth.frame.push_back(static_cast<long>(k));
    truth.time.push_back(recording.time_s(k));
    truth.values.row(k) << pose.root_position.transpose(), pose.root_rpy.transpose(), pose.joints.transpose();
  }
  return truth;
}

/// The simulated recording as marker data (what the C3D reader would hand over).
MarkerSequence as_c3d(const sim::Recording& recording) { return recording; }

MarkerSequence bundled_handstand(Eigen::Index frames) {
  const MarkerSequence all = c3d::read_c3d(data_file("handstand.c3d"));
  return all.frames(0, std::min(frames, all.frame_count()));
}

TEST(GradientBaseline, ConvergesToTheTruthOnExactFrames) {
  const sim::Recording recording = exact_handstand(60, 1750);
  const body::BodyModel model = body::mmm_body_model(1000).scaled(1750);
  const body::MarkerMapping mapping = body::map_markers(recording.labels, model.marker_names());
  track::GradientBaseline baseline(model, mapping);
  Eigen::Index f = 0;
  auto next = [&](MarkerFrame& frame) {
    if (f >= recording.frames()) return false;
    frame.index = f;
    frame.positions = recording.frame(f);
    frame.visible = recording.visible.col(f);
    ++f;
    return true;
  };
  int most_iterations = 0;
  const track::TrackingRun run =
      track::run_tracking(baseline, next, recording.rate_hz, model.joint_names(), false, [&](long index) {
        if (index > 0) most_iterations = std::max(most_iterations, baseline.last_iterations());
      });
  for (double d : run.mean_marker_distance) EXPECT_LT(d, 0.05);  // mm, every frame, the first included
  const evaluation::TruthComparison truth =
      evaluation::compare_with_truth(model, run.motion, truth_table(recording, model), 0);
  EXPECT_LT(truth.segment_orientation_rms_deg, 0.05);
  EXPECT_LT(truth.limb_flexion_rms_deg, 0.1);
  EXPECT_LT(truth.root_position_rms_mm, 0.05);
  EXPECT_EQ(truth.joint_limit_violations, 0);
  // Warm-started from the previous frame, it needs only a few iterations per frame.
  EXPECT_LE(most_iterations, 15);

  // The evaluation's path (setup from the labels, the given height) gives the same fit.
  const MarkerSequence c3d_recording = as_c3d(recording);
  const pipeline::Session setup = evaluation_session(c3d_recording, 1750);
  const io::MotionTable truth_motion = truth_table(recording, model);
  const evaluation::MethodResult evaluated =
      evaluation::evaluate_method(setup, c3d_recording, pipeline::Method::baseline, 0, &truth_motion, 0);
  EXPECT_LT(evaluated.worst_all_frames_mm, 0.05);
  ASSERT_TRUE(evaluated.truth.has_value());
  EXPECT_LT(evaluated.truth->segment_orientation_rms_deg, 0.05);
}

/// Fits one set of model markers (three frames, warm-started) and returns the estimate.
track::FrameEstimate fit_points(const body::BodyModel& model, const Eigen::Matrix3Xd& points) {
  const body::MarkerMapping mapping = body::map_markers(model.marker_names(), model.marker_names());
  const Eigen::Array<bool, Eigen::Dynamic, 1> visible =
      Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(points.cols(), true);
  track::GradientBaseline baseline(model, mapping);
  for (int frame = 0; frame < 3; ++frame) baseline.process(points, visible);
  return baseline.estimate();
}

void expect_within_limits(const body::BodyModel& model, const Eigen::VectorXd& joints) {
  for (int j = 0; j < model.joint_count(); ++j) {
    EXPECT_GE(joints(j), model.joints[j].lower) << model.joints[j].name;
    EXPECT_LE(joints(j), model.joints[j].upper) << model.joints[j].name;
  }
}

TEST(GradientBaseline, FindsATruthThatLiesOnJointLimits) {
  const body::BodyModel model = body::mmm_body_model(1750);
  const int knee = model.joint_index("LKx"), elbow = model.joint_index("REx");
  ASSERT_GE(knee, 0);
  ASSERT_GE(elbow, 0);
  body::Pose pose;
  pose.root_position = Eigen::Vector3d(100, -50, 1000);
  pose.joints(knee) = model.joints[knee].upper;
  pose.joints(elbow) = model.joints[elbow].lower;
  const Eigen::Matrix3Xd points = body::marker_positions(model, pose);
  const track::FrameEstimate estimate = fit_points(model, points);
  expect_within_limits(model, estimate.pose.joints);
  EXPECT_NEAR(estimate.pose.joints(knee), model.joints[knee].upper, 1e-4);
  EXPECT_NEAR(estimate.pose.joints(elbow), model.joints[elbow].lower, 1e-3);
  EXPECT_LT((estimate.predicted_markers - points).colwise().norm().maxCoeff(), 0.01);  // mm
}

TEST(GradientBaseline, StaysOnTheLimitWhenTheMarkersAskForMore) {
  const body::BodyModel model = body::mmm_body_model(1750);
  const int knee = model.joint_index("LKx");
  ASSERT_GE(knee, 0);
  body::Pose pose;
  pose.root_position = Eigen::Vector3d(100, -50, 1000);
  pose.joints(knee) = model.joints[knee].upper + 0.15;  // bent past its range
  const Eigen::Matrix3Xd points = body::marker_positions(model, pose);
  const track::FrameEstimate estimate = fit_points(model, points);
  expect_within_limits(model, estimate.pose.joints);
  EXPECT_NEAR(estimate.pose.joints(knee), model.joints[knee].upper, 1e-9);
  // The constrained optimum is at least as good as the truth projected onto the limits (a
  // feasible pose), and the fit is not exact (the markers ask for more than the limit allows).
  body::Pose projected = pose;
  projected.joints(knee) = model.joints[knee].upper;
  const double projected_cost = (body::marker_positions(model, projected) - points).squaredNorm();
  const double fitted_cost = (estimate.predicted_markers - points).squaredNorm();
  EXPECT_LE(fitted_cost, projected_cost * (1 + 1e-9));
  EXPECT_GT(fitted_cost, 1.0);  // mm^2
}

TEST(Evaluation, MethodsAgreeWithTheirOwnTrackingRuns) {
  const MarkerSequence recording = bundled_handstand(60);
  const pipeline::Session setup = evaluation_session(recording);
  const io::MotionTable truth =
      evaluation::first_rows(io::load_motion_csv(data_file("handstand_truth.csv")), 60);
  evaluation::check_truth(truth, setup, 60);
  const evaluation::MethodResult s2kf =
      evaluation::evaluate_method(setup, recording, pipeline::Method::s2kf, 93, &truth, 20);
  const evaluation::MethodResult baseline =
      evaluation::evaluate_method(setup, recording, pipeline::Method::baseline, 0, &truth, 20);

  // The same trackers run by hand through run_tracking.
  Eigen::Index f = 0;
  auto next = [&](MarkerFrame& frame) {
    if (f >= recording.frame_count()) return false;
    frame.index = f;
    frame.positions = recording.frame(f);
    frame.visible = recording.visible.col(f);
    ++f;
    return true;
  };
  track::TrackerOptions options;
  options.samples = 93;
  track::Tracker tracker(setup.model, setup.mapping, options, recording.rate_hz,
                         test::tracker_samples(options));
  const track::TrackingRun by_hand =
      track::run_tracking(tracker, next, recording.rate_hz, setup.model.joint_names());
  f = 0;
  track::GradientBaseline gradient(setup.model, setup.mapping);
  const track::TrackingRun by_hand_baseline =
      track::run_tracking(gradient, next, recording.rate_hz, setup.model.joint_names());

  ASSERT_EQ(s2kf.run.mean_marker_distance.size(), 60u);
  for (std::size_t k = 0; k < 60; ++k) {
    EXPECT_DOUBLE_EQ(s2kf.run.mean_marker_distance[k], by_hand.mean_marker_distance[k]) << k;
    EXPECT_DOUBLE_EQ(baseline.run.mean_marker_distance[k], by_hand_baseline.mean_marker_distance[k]) << k;
  }
  const long converged =
      track::converged_frame(by_hand.mean_marker_distance, track::frames_per_second(recording.rate_hz));
  EXPECT_EQ(s2kf.converged_frame, converged);
  EXPECT_DOUBLE_EQ(s2kf.level_mm, track::mean_from(by_hand.mean_marker_distance, converged));
  const evaluation::TruthComparison direct =
      evaluation::compare_with_truth(setup.model, by_hand.motion, truth, 20);
  ASSERT_TRUE(s2kf.truth.has_value());
  EXPECT_DOUBLE_EQ(s2kf.truth->segment_orientation_rms_deg, direct.segment_orientation_rms_deg);
  EXPECT_EQ(s2kf.truth->frames, 40);
  // Both track the synthetic handstand to centimetres; the worst frame is no better than the mean.
  EXPECT_LT(s2kf.level_mm, 40);
  EXPECT_LT(baseline.level_mm, 40);
  EXPECT_GE(s2kf.worst_mm, s2kf.level_mm);
  EXPECT_GT(s2kf.median_ms, 0);
  EXPECT_GE(s2kf.p99_ms, s2kf.median_ms);
}

TEST(Evaluation, OcclusionStudyHidesWhatTheProcessHidesAndMeasuresAgainstAllMarkers) {
  const MarkerSequence recording = bundled_handstand(60);
  const pipeline::Session setup = evaluation_session(recording);
  evaluation::OcclusionOptions options;
  options.runs = 2;
  options.samples = 93;
  options.seed = 11;
  options.occlusion.probability = 0.02;  // more than the paper's, so 60 frames hide something
  options.occlusion.mean_frames = 20;
  const evaluation::OcclusionStudy study = evaluation::occlusion_monte_carlo(setup, recording, options, 20);
  ASSERT_EQ(study.hidden.size(), 2u);
  EXPECT_EQ(study.markers, 50);
  double sum = 0;
  for (int r = 0; r < 2; ++r) {
    // The same process, run independently with the documented seed.
    std::mt19937_64 rng(sim::derive_seed(11, static_cast<std::uint64_t>(r)));
    sim::Visibility keep = sim::Visibility::Constant(recording.point_count(), 60, true);
    sim::apply_random_occlusion(keep, options.occlusion, rng);
    for (Eigen::Index k = 0; k < 60; ++k) {
      EXPECT_EQ(study.hidden[r][static_cast<std::size_t>(k)], static_cast<int>((!keep.col(k)).count())) << k;
      sum += study.hidden[r][static_cast<std::size_t>(k)];
    }
  }
  EXPECT_GT(sum, 0);
  EXPECT_NEAR(study.mean_hidden_overall, sum / 120, 1e-12);
  for (std::size_t k = 0; k < 60; ++k) {
    EXPECT_NEAR(study.mean_hidden[k], (study.hidden[0][k] + study.hidden[1][k]) / 2.0, 1e-12);
    EXPECT_LE(study.s2kf.min[k], study.s2kf.mean[k]);
    EXPECT_LE(study.s2kf.mean[k], study.s2kf.max[k]);
    EXPECT_DOUBLE_EQ(study.s2kf.min[k], std::min(study.s2kf_distance[0][k], study.s2kf_distance[1][k]));
  }
  // Without occlusion every marker is shown, so the distance against all markers is the
  // tracker's own per-frame distance.
  options.occlusion.probability = 0;
  options.runs = 1;
  const evaluation::OcclusionStudy clear = evaluation::occlusion_monte_carlo(setup, recording, options, 20);
  const evaluation::MethodResult s2kf =
      evaluation::evaluate_method(setup, recording, pipeline::Method::s2kf, 93, nullptr, 20);
  const evaluation::MethodResult baseline =
      evaluation::evaluate_method(setup, recording, pipeline::Method::baseline, 0, nullptr, 20);
  for (std::size_t k = 0; k < 60; ++k) {
    EXPECT_EQ(clear.hidden[0][k], 0);
    EXPECT_NEAR(clear.s2kf_distance[0][k], s2kf.run.mean_marker_distance[k], 1e-9) << k;
    EXPECT_NEAR(clear.baseline_distance[0][k], baseline.run.mean_marker_distance[k], 1e-9) << k;
  }
}

TEST(Evaluation, DistanceAgainstAllMarkersCountsHiddenOnes) {
  const body::BodyModel model = body::mmm_body_model(1750);
  const body::MarkerMapping mapping = body::map_markers(model.marker_names(), model.marker_names());
  const Eigen::Matrix3Xd predicted = body::marker_positions(model, body::Pose{});
  Eigen::Matrix3Xd reference = predicted;
  reference(0, 0) += 50;  // one marker 50 mm off, the rest exact
  Eigen::Array<bool, Eigen::Dynamic, 1> visible =
      Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(predicted.cols(), true);
  EXPECT_NEAR(evaluation::mean_marker_distance(predicted, reference, visible, mapping),
              50.0 / model.marker_count(), 1e-12);
  visible(0) = false;  // a marker the reference itself lacks does not count
  EXPECT_NEAR(evaluation::mean_marker_distance(predicted, reference, visible, mapping), 0.0, 1e-12);
}

TEST(Evaluation, SampleSweepRunsEachCount) {
  const MarkerSequence recording = bundled_handstand(20);
  const pipeline::Session setup = evaluation_session(recording);
  const auto sweep = evaluation::sample_sweep(setup, recording, {93, 101}, nullptr, 5);
  ASSERT_EQ(sweep.size(), 2u);
  EXPECT_EQ(sweep[0].samples, 93);
  EXPECT_EQ(sweep[1].samples, 101);
  for (const auto& r : sweep) EXPECT_EQ(r.run.mean_marker_distance.size(), 20u);
  EXPECT_NE(sweep[0].run.mean_marker_distance.back(), sweep[1].run.mean_marker_distance.back());
}

TEST(Evaluation, TruthThatDoesNotFitIsRejected) {
  const MarkerSequence recording = bundled_handstand(10);
  const pipeline::Session setup = evaluation_session(recording);
  io::MotionTable truth = evaluation::first_rows(io::load_motion_csv(data_file("handstand_truth.csv")), 10);
  EXPECT_NO_THROW(evaluation::check_truth(truth, setup, 10));
  EXPECT_THROW(evaluation::check_truth(truth, setup, 11), std::invalid_argument);
  truth.joint_names[3] = "elbow";
  EXPECT_THROW(evaluation::check_truth(truth, setup, 10), std::invalid_argument);
}

}  // namespace
