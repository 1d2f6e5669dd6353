// The whole-body tracking step on real frames of data/handstand.c3d, the forward kinematics of
// its samples and a floor: the work no implementation of the step can avoid (L forward kinematics
// of one pose each and one symmetric rank-L update of the observed-measurement covariance). The
// filter's other parts are timed by bench_track_parts. docs/benchmarks.md has the numbers and the
// commands.
#include "track_scenario.hpp"

#include <benchmark/benchmark.h>

namespace {

using namespace track_bench;

// One steady-state frame with the default options: prediction, sampling, batched FK, moments, gain
// (information form), update, re-centring and the reported pose, markers and distances
// (Tracker::process). Counters, each floor the median of 30 in this process at this L and visible
// count: floor_us (FK + the rank-L update of the whole innovation covariance) and x_floor (this
// step / floor); regression_floor_us (FK + the regression G^T, the least a linear-regression
// filter does) and x_regression_floor.
void BM_TrackStep(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  const int visible = static_cast<int>(state.range(1));
  const Scenario& s = Scenario::get();
  const auto& visibility = s.visibility(visible);
  track::Tracker tracker = warmed_tracker(samples);
  const std::size_t frame_count = s.frames.size();
  std::size_t f = kWarmupFrames;
  long failures = 0;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    const track::FrameEstimate& e = tracker.process(s.frames[f], visibility[f]);
    failures += e.status != FilterStatus::ok;
    benchmark::DoNotOptimize(e.pose.joints.data());
    if (++f == frame_count) f = kWarmupFrames;  // the jump back costs the same work
  }
  const double step = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() /
                      static_cast<double>(state.iterations());
  const ConvergedState c = converged_state(samples);
  Floor floor(c, lcd_sample_set(46, samples).set, visible);
  const double floor_seconds = median_seconds(30, [&] { floor.run(); });
  state.counters["floor_us"] = 1e6 * floor_seconds;
  state.counters["x_floor"] = step / floor_seconds;
  const double regression_floor_seconds = median_seconds(30, [&] { floor.run_regression(); });
  state.counters["regression_floor_us"] = 1e6 * regression_floor_seconds;
  state.counters["x_regression_floor"] = step / regression_floor_seconds;
  state.counters["failed_updates"] = static_cast<double>(failures);
}
BENCHMARK(BM_TrackStep)->Apply(add_args);

// The steady-state step of a tracker with other options, on the same frames as BM_TrackStep.
void run_step_with(benchmark::State& state, track::TrackerOptions options) {
  const Scenario& s = Scenario::get();
  const auto& visibility = s.visibility(static_cast<int>(state.range(1)));
  options.samples = static_cast<int>(state.range(0));
  track::Tracker tracker(s.model, s.mapping, options, s.rate, lcd_sample_set(46, options.samples).set);
  for (int f = 0; f < kWarmupFrames; ++f) tracker.process(s.frames[f], s.all_visible[f]);
  std::size_t f = kWarmupFrames;
  for (auto _ : state) {
    const track::FrameEstimate& e = tracker.process(s.frames[f], visibility[f]);
    benchmark::DoNotOptimize(e.pose.joints.data());
    if (++f == s.frames.size()) f = kWarmupFrames;
  }
}

// The same step with the moments summed in double (TrackerOptions::single_precision_moments off):
// what single precision saves.
void BM_TrackStepDouble(benchmark::State& state) {
  track::TrackerOptions options;
  options.single_precision_moments = false;
  run_step_with(state, options);
}
BENCHMARK(BM_TrackStepDouble)->Apply(add_args);

// The same step with the ordinary (square-root) gain (TrackerOptions::information_form_update
// off): the whole innovation covariance Cyy, its Cholesky factor and the solves with it, instead
// of each body part's block of Cyy and the 46 x 46 information matrix.
void BM_TrackStepSquareRoot(benchmark::State& state) {
  track::TrackerOptions options;
  options.information_form_update = false;
  run_step_with(state, options);
}
BENCHMARK(BM_TrackStepSquareRoot)->Apply(add_args);

// The same step with the constant-velocity model (92-state prediction, the 46-dimensional sampled
// update, the rates conditioned on it): the latency it adds at the same L.
void BM_TrackStepConstantVelocity(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  const Scenario& s = Scenario::get();
  const auto& visibility = s.visibility(static_cast<int>(state.range(1)));
  track::Tracker tracker = warmed_tracker(samples, track::MotionModel::constant_velocity);
  std::size_t f = kWarmupFrames;
  for (auto _ : state) {
    const track::FrameEstimate& e = tracker.process(s.frames[f], visibility[f]);
    benchmark::DoNotOptimize(e.pose.joints.data());
    if (++f == s.frames.size()) f = kWarmupFrames;
  }
}
BENCHMARK(BM_TrackStepConstantVelocity)
    ->Args({301, 50})
    ->Args({301, 34})
    ->ArgNames({"L", "visible"})
    ->Unit(benchmark::kMicrosecond);

// The floors alone and their parts: one member of the Floor at this benchmark's {L, visible}.
void run_floor_part(benchmark::State& state, void (Floor::*part)()) {
  const int samples = static_cast<int>(state.range(0));
  const int visible = static_cast<int>(state.range(1));
  Floor floor(converged_state(samples), lcd_sample_set(46, samples).set, visible);
  for (auto _ : state) (floor.*part)();
}

void BM_Floor(benchmark::State& state) { run_floor_part(state, &Floor::run); }
BENCHMARK(BM_Floor)->Apply(add_args);

void BM_FloorRegression(benchmark::State& state) { run_floor_part(state, &Floor::regression); }
BENCHMARK(BM_FloorRegression)->Apply(add_args);

void BM_FloorSinglePoseFk(benchmark::State& state) { run_floor_part(state, &Floor::single_pose_fk); }
BENCHMARK(BM_FloorSinglePoseFk)->Args({301, 50})->ArgNames({"L", "visible"})->Unit(benchmark::kMicrosecond);

void BM_FloorRankUpdate(benchmark::State& state) { run_floor_part(state, &Floor::rank_update); }
BENCHMARK(BM_FloorRankUpdate)->Apply(add_args);

// The first frame (10 passes of posterior linearisation from the rigid-fit start) and one of the
// converging frames 1..5 (3 passes each), which the steady-state figure leaves out.
void BM_TrackFirstFrames(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  const int frames = static_cast<int>(state.range(1));
  const Scenario& s = Scenario::get();
  track::TrackerOptions options;
  options.samples = samples;
  const track::Tracker fresh(s.model, s.mapping, options, s.rate, lcd_sample_set(46, options.samples).set);
  for (auto _ : state) {
    state.PauseTiming();
    auto tracker = std::make_unique<track::Tracker>(fresh);
    state.ResumeTiming();
    for (int f = 0; f < frames; ++f)
      benchmark::DoNotOptimize(tracker->process(s.frames[f], s.all_visible[f]).nis);
    state.PauseTiming();
    tracker.reset();
    state.ResumeTiming();
  }
}
BENCHMARK(BM_TrackFirstFrames)
    ->Args({301, 1})
    ->Args({301, 6})
    ->ArgNames({"L", "frames"})
    ->Unit(benchmark::kMicrosecond);

// ---- Parts of the step, on the converged state ----

// Batched FK of the whole sample block through the tracker's measurement model, in double as the
// tracker runs it by default (BM_PartForwardKinematicsSingle: in float).
void forward_kinematics_part(benchmark::State& state, bool single) {
  const int samples = static_cast<int>(state.range(0));
  ConvergedState c = converged_state(samples);
  c.model.set_single_precision(single);
  const Eigen::MatrixXd x = draw(c, lcd_sample_set(46, samples).set);
  Eigen::MatrixXd y(c.model.measurement_dimension(), x.cols());
  for (auto _ : state) {
    c.model(x, y);
    benchmark::DoNotOptimize(y.data());
  }
}
void BM_PartForwardKinematics(benchmark::State& state) { forward_kinematics_part(state, false); }
BENCHMARK(BM_PartForwardKinematics)->Apply(add_args);
void BM_PartForwardKinematicsSingle(benchmark::State& state) { forward_kinematics_part(state, true); }
BENCHMARK(BM_PartForwardKinematicsSingle)
    ->Args({301, 50})
    ->ArgNames({"L", "visible"})
    ->Unit(benchmark::kMicrosecond);

// The same samples as the tracker evaluates them by default (evaluate_symmetric_deviations): each
// sample as its float deviation from the mean pose (the LCD set is symmetric: origin, + half, -
// half), handed on in float. The mean pose itself is kept between calls about the same mean, as
// the tracker keeps the one it reported its markers at.
void BM_PartForwardKinematicsDeviations(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  ConvergedState c = converged_state(samples);
  c.model.set_single_precision_deviations(true);
  const SampleSet set = lcd_sample_set(46, samples).set;
  const Eigen::MatrixXd x = draw(c, set);
  const Eigen::Index h = samples / 2, origin = samples % 2;
  const Eigen::MatrixXf half = (x.middleCols(origin, h).colwise() - c.state.mean).cast<float>();
  Eigen::MatrixXf y(c.model.measurement_dimension(), x.cols());
  Eigen::VectorXd at_mean(c.model.measurement_dimension());
  for (auto _ : state) {
    c.model.evaluate_symmetric_deviations(c.state.mean, half, origin, y, at_mean);
    benchmark::DoNotOptimize(y.data());
  }
}
BENCHMARK(BM_PartForwardKinematicsDeviations)->Apply(add_args);

}  // namespace

BENCHMARK_MAIN();
