/// @file
/// What the tracking-step benchmarks share (bench_track.cpp: the step and its floor;
/// bench_track_parts.cpp: the filter's parts on the converged state): real frames of
/// data/handstand.c3d, a warmed tracker and the floor.
///
/// Arguments are {L, visible markers}: 50 is every marker of the recording, 34 hides 16 of them in
/// a pattern that moves along the marker list every 10 frames (the seed paper's average occlusion).
#pragma once

#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/marker_measurement_model.hpp>
#include <s2kf/calibration/height_estimate.hpp>
#include <s2kf/core/product_tiles.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/sample_cache.hpp>
#include <s2kf/track/tracker.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace track_bench {

using namespace s2kf;

using namespace s2kf;
using Visible = Eigen::Array<bool, Eigen::Dynamic, 1>;

constexpr int kWarmupFrames = 30;  // past the iterated (converging) frames: a converged covariance

/// The handstand recording, its body model scaled as `s2kf track` scales it, and every frame with
/// both visibility patterns.
struct Scenario {
  body::BodyModel model;
  body::MarkerMapping mapping;
  double rate = 0;
  std::vector<Eigen::Matrix3Xd> frames;
  std::vector<Visible> all_visible, some_hidden;

  static const Scenario& get() {
    static const Scenario scenario = make();
    return scenario;
  }

  const std::vector<Visible>& visibility(int visible_markers) const {
    return visible_markers >= 50 ? all_visible : some_hidden;
  }

 private:
  static Scenario make() {
    const c3d::Recording recording = c3d::read_c3d(std::string(S2KF_DATA_DIR) + "/handstand.c3d");
    Scenario s;
    std::vector<std::string> labels;
    for (const auto& label : recording.info.labels) labels.push_back(label.name);
    s.model = body::mmm_body_model(1000);
    s.mapping = body::map_markers(labels, s.model.marker_names());
    calibration::HeightEstimator heights(s.model, s.mapping);
    const Eigen::Index step = std::max<Eigen::Index>(1, recording.frame_count() / 200);
    for (Eigen::Index f = 0; f < recording.frame_count(); f += step)
      heights.add_frame(recording.frame(f), recording.visible.col(f));
    s.model = s.model.scaled(heights.height_mm().value_or(1750));
    s.rate = recording.info.rate;
    const Eigen::Index points = recording.point_count();
    for (Eigen::Index f = 0; f < recording.frame_count(); ++f) {
      s.frames.emplace_back(recording.frame(f));
      s.all_visible.emplace_back(recording.visible.col(f));
      Visible some = recording.visible.col(f);
      for (Eigen::Index p = 0; p < points; ++p)
        if ((p + 3 * (f / 10)) % points < 16) some(p) = false;
      s.some_hidden.push_back(some);
    }
    return s;
  }
};

/// A tracker with L samples that has run the first kWarmupFrames frames (every marker visible).
inline track::Tracker warmed_tracker(int samples,
                                     track::MotionModel motion_model = track::TrackerOptions{}.motion_model) {
  const Scenario& s = Scenario::get();
  track::TrackerOptions options;
  options.samples = samples;
  options.motion_model = motion_model;
  track::Tracker tracker(s.model, s.mapping, options, s.rate, lcd_sample_set(46, options.samples).set);
  for (int f = 0; f < kWarmupFrames; ++f) tracker.process(s.frames[f], s.all_visible[f]);
  return tracker;
}

/// The converged state of a warmed tracker, as the filter sees it at the next update: the mean
/// (orientation error 0 about the tracker's reference) and the predicted covariance.
struct ConvergedState {
  GaussianXd state;
  Eigen::Matrix3d reference;
  body::MarkerMeasurementModel model;
};

inline ConvergedState converged_state(int samples) {
  const Scenario& s = Scenario::get();
  const track::Tracker tracker = warmed_tracker(samples);
  body::MarkerMeasurementModel h(s.model, body::OrientationParameterization::local_rotation_error);
  h.select_markers(tracker.used_markers());
  h.set_reference_orientation(tracker.estimate().root_rotation);
  GaussianXd state;
  state.mean = h.state(tracker.estimate().pose);
  state.covariance = tracker.estimate().covariance;
  state.covariance.diagonal().array() += 1e-3;  // the random-walk prediction, roughly
  return {state, tracker.estimate().root_rotation, h};
}

/// Samples x_i = m + S z_i of the converged state with the tracker's sample set.
inline Eigen::MatrixXd draw(const ConvergedState& c, const SampleSet& set) {
  const Eigen::MatrixXd factor = c.state.covariance.llt().matrixL();
  Eigen::MatrixXd x = factor * set.points;
  x.colwise() += c.state.mean;
  return x;
}

/// Median seconds of `reps` calls of f.
template <typename F>
double median_seconds(int reps, F&& f) {
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    const auto start = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::nth_element(t.begin(), t.begin() + reps / 2, t.end());
  return t[reps / 2];
}

/// The floors: the work no sampling step can avoid, each part by the fastest kernel the project
/// has and in the precision the tracker uses for it. run(): the batched FK of the L samples (the
/// measurement model on the whole block, double) and one symmetric rank-L update of the
/// (3 visible)^2 covariance of the predicted markers (single), the floor of an update that forms
/// the whole innovation covariance. run_regression(): the same FK and the regression of the
/// predictions on the unit samples, G^T = sum over the L/2 pairs of z_k (y+_k - y-_k)^T (single),
/// the least any linear-regression Kalman filter must do (it needs the cross-covariance at least).
struct Floor {
  std::vector<body::Pose> poses;
  Eigen::MatrixXd x, y;
  Eigen::MatrixXf deviations, cyy, unit_half, pair_difference, regression_t;
  body::MarkerMeasurementModel h;
  body::BodyModel model;

  Floor(const ConvergedState& c, const SampleSet& set, int visible_markers)
      : x(draw(c, set)), h(c.model), model(c.model.model()) {
    for (Eigen::Index i = 0; i < x.cols(); ++i) poses.push_back(c.model.pose(x.col(i)));
    y.resize(h.measurement_dimension(), x.cols());
    h(x, y);
    Eigen::MatrixXd d = y.topRows(3 * visible_markers);
    d.colwise() -= d.rowwise().mean();
    deviations = d.cast<float>();
    cyy = Eigen::MatrixXf::Identity(deviations.rows(), deviations.rows());
    const Eigen::Index h = set.count() / 2, o = set.count() % 2;
    unit_half = set.points.middleCols(o, h).cast<float>();
    pair_difference = deviations.middleCols(o, h) - deviations.rightCols(h);
    regression_t.resize(unit_half.rows(), deviations.rows());
  }
  void fk() {
    h(x, y);
    benchmark::DoNotOptimize(y.data());
  }
  /// L calls of the single-pose FK (allocating; for comparison only).
  void single_pose_fk() {
    for (const body::Pose& pose : poses) {
      Eigen::Matrix3Xd markers = body::marker_positions(model, pose);
      benchmark::DoNotOptimize(markers.data());
    }
  }
  void rank_update() {
    s2kf::add_self_product_lower(cyy, deviations);
    benchmark::DoNotOptimize(cyy.data());
  }
  void regression() {
    regression_t.setZero();
    s2kf::add_product_transposed(regression_t, unit_half, pair_difference);
    benchmark::DoNotOptimize(regression_t.data());
  }
  void run() {
    fk();
    rank_update();
  }
  void run_regression() {
    fk();
    regression();
  }
};

inline void add_args(benchmark::internal::Benchmark* b) {
  for (int visible : {50, 34})
    for (int samples : {93, 101, 201, 301, 461, 1001}) b->Args({samples, visible});
  b->ArgNames({"L", "visible"})->Unit(benchmark::kMicrosecond);
}

}  // namespace track_bench
