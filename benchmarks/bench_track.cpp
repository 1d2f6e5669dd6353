// The whole-body tracking step on real frames of data/handstand.c3d, its parts, and a floor: the
// work no implementation of the step can avoid (L forward kinematics of one pose each and one
// symmetric rank-L update of the observed-measurement covariance). docs/benchmarks.md has the
// numbers and the commands.
//
// Arguments are {L, visible markers}: 50 is every marker of the recording, 34 hides 16 of them in a
// pattern that moves along the marker list every 10 frames (the seed paper's average occlusion).
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_measurement_model.hpp>
#include <s2kf/core/sample_cache.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/track/height_estimate.hpp>
#include <s2kf/track/marker_mapping.hpp>
#include <s2kf/track/tracker.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace s2kf;
using Visible = Eigen::Array<bool, Eigen::Dynamic, 1>;

constexpr int kWarmupFrames = 30;  // past the iterated (converging) frames: a converged covariance

/// The handstand recording, its body model scaled as `s2kf track` scales it, and every frame with
/// both visibility patterns.
struct Scenario {
  body::BodyModel model;
  track::MarkerMapping mapping;
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
    s.mapping = track::map_markers(labels, s.model.marker_names());
    track::HeightEstimator heights(s.model, s.mapping);
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
track::Tracker warmed_tracker(int samples,
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

ConvergedState converged_state(int samples) {
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
Eigen::MatrixXd draw(const ConvergedState& c, const SampleSet& set) {
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

/// The floor: the work no sampling step can avoid, each part by the fastest kernel the project
/// has and in the precision the tracker uses for it: the batched FK of the L samples (the
/// measurement model on the whole block, double) and one symmetric rank-L update of the
/// (3 visible)^2 covariance of the predicted markers (single). Returns seconds (median of `reps`).
struct Floor {
  std::vector<body::Pose> poses;
  Eigen::MatrixXd x, y;
  Eigen::MatrixXf deviations, cyy;
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
    cyy.selfadjointView<Eigen::Lower>().rankUpdate(deviations);
    benchmark::DoNotOptimize(cyy.data());
  }
  void run() {
    fk();
    rank_update();
  }
};

void add_args(benchmark::internal::Benchmark* b) {
  for (int visible : {50, 34})
    for (int samples : {93, 101, 201, 301, 461, 1001}) b->Args({samples, visible});
  b->ArgNames({"L", "visible"})->Unit(benchmark::kMicrosecond);
}

// One steady-state frame: prediction, sampling, batched FK, moments, gain, update, re-centring and
// the reported pose, markers and distances (Tracker::process). Counters: floor_us (the floor at
// this L and visible count, median of 30 in this process) and x_floor (this step / floor).
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
  state.counters["failed_updates"] = static_cast<double>(failures);
}
BENCHMARK(BM_TrackStep)->Apply(add_args);

// The same step with the moments summed in double (TrackerOptions::single_precision_moments off):
// what single precision saves.
void BM_TrackStepDouble(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  const Scenario& s = Scenario::get();
  const auto& visibility = s.visibility(static_cast<int>(state.range(1)));
  track::TrackerOptions options;
  options.samples = samples;
  options.single_precision_moments = false;
  track::Tracker tracker(s.model, s.mapping, options, s.rate, lcd_sample_set(46, samples).set);
  for (int f = 0; f < kWarmupFrames; ++f) tracker.process(s.frames[f], s.all_visible[f]);
  std::size_t f = kWarmupFrames;
  for (auto _ : state) {
    const track::FrameEstimate& e = tracker.process(s.frames[f], visibility[f]);
    benchmark::DoNotOptimize(e.pose.joints.data());
    if (++f == s.frames.size()) f = kWarmupFrames;
  }
}
BENCHMARK(BM_TrackStepDouble)->Apply(add_args);

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

// The floor alone, and its two halves.
void BM_Floor(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  const int visible = static_cast<int>(state.range(1));
  Floor floor(converged_state(samples), lcd_sample_set(46, samples).set, visible);
  for (auto _ : state) floor.run();
}
BENCHMARK(BM_Floor)->Apply(add_args);

void BM_FloorSinglePoseFk(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  Floor floor(converged_state(samples), lcd_sample_set(46, samples).set, 50);
  for (auto _ : state) floor.single_pose_fk();
}
BENCHMARK(BM_FloorSinglePoseFk)->Args({301, 50})->ArgNames({"L", "visible"})->Unit(benchmark::kMicrosecond);

void BM_FloorRankUpdate(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  const int visible = static_cast<int>(state.range(1));
  Floor floor(converged_state(samples), lcd_sample_set(46, samples).set, visible);
  for (auto _ : state) floor.rank_update();
}
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

// The filter's update without FK: the measurement model hands back a stored prediction block,
// so this is sampling, moments (in single precision, as the tracker sums them), factorisation,
// gain, update and the posterior check.
void BM_PartFilterWithoutFk(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  const int visible = static_cast<int>(state.range(1));
  const Scenario& s = Scenario::get();
  ConvergedState c = converged_state(samples);
  const SampleSet set = lcd_sample_set(46, samples).set;
  const Eigen::MatrixXd x = draw(c, set);
  Eigen::MatrixXd y(c.model.measurement_dimension(), x.cols());
  c.model(x, y);
  const auto stored = [&](const Eigen::MatrixXd&, Eigen::MatrixXd& out) { out = y; };
  Eigen::VectorXd measurement = y.rowwise().mean();
  ObservedMask observed = ObservedMask::Constant(measurement.size(), true);
  observed.tail(3 * (50 - visible)).setConstant(false);
  const Eigen::MatrixXd r = body::marker_noise(100.0, measurement.size() / 3);
  S2kf filter(set);
  UpdateOptions options;
  options.single_precision_moments = true;
  GaussianXd work = c.state;
  (void)s;
  for (auto _ : state) {
    work.mean = c.state.mean;  // small copies (46 + 46^2 doubles), no allocation
    work.covariance = c.state.covariance;
    benchmark::DoNotOptimize(filter.update(work, stored, measurement, r, observed, options).nis);
  }
}
BENCHMARK(BM_PartFilterWithoutFk)->Apply(add_args);

/// Deviations of the predicted markers and states of the converged state (weights 1/L).
struct Moments {
  Eigen::MatrixXd y_dev, x_dev, cyy, cyx;
  Moments(int samples, int visible) {
    ConvergedState c = converged_state(samples);
    const Eigen::MatrixXd x = draw(c, lcd_sample_set(46, samples).set);
    Eigen::MatrixXd y(c.model.measurement_dimension(), x.cols());
    c.model(x, y);
    const double root_w = 1.0 / std::sqrt(static_cast<double>(samples));
    y_dev = root_w * y.topRows(3 * visible);
    y_dev.colwise() -= y_dev.rowwise().mean();
    x_dev = root_w * x;
    x_dev.colwise() -= x_dev.rowwise().mean();
    cyy = 100.0 * Eigen::MatrixXd::Identity(y_dev.rows(), y_dev.rows());
    cyy.selfadjointView<Eigen::Lower>().rankUpdate(y_dev);
    cyx = y_dev * x_dev.transpose();
  }
};

// Cyy by a symmetric rank-L update (lower half) and Cyx by a product over all samples (the
// filter before this work).
void BM_PartCyy(benchmark::State& state) {
  Moments m(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  Eigen::MatrixXd cyy = m.cyy;
  for (auto _ : state) {
    cyy.selfadjointView<Eigen::Lower>().rankUpdate(m.y_dev);
    benchmark::DoNotOptimize(cyy.data());
  }
}
BENCHMARK(BM_PartCyy)->Apply(add_args);

void BM_PartCyx(benchmark::State& state) {
  Moments m(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  for (auto _ : state) {
    m.cyx.noalias() = m.y_dev * m.x_dev.transpose();
    benchmark::DoNotOptimize(m.cyx.data());
  }
}
BENCHMARK(BM_PartCyx)->Apply(add_args);

// Cyx as the filter forms it for a symmetric set: sum over pairs of sqrt(w)(y+ - y-) times
// sqrt(w) s^T, half the product above (the difference of the pair columns included).
void BM_PartCyxPaired(benchmark::State& state) {
  Moments m(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const Eigen::Index h = m.y_dev.cols() / 2, o = m.y_dev.cols() % 2;
  const Eigen::MatrixXd half_x = m.x_dev.middleCols(o, h);
  Eigen::MatrixXd difference(m.y_dev.rows(), h);
  for (auto _ : state) {
    difference.noalias() = m.y_dev.middleCols(o, h) - m.y_dev.rightCols(h);
    m.cyx.noalias() = difference * half_x.transpose();
    benchmark::DoNotOptimize(m.cyx.data());
  }
}
BENCHMARK(BM_PartCyxPaired)->Apply(add_args);

// Cholesky factorisation of Cyy in place (size 3 x visible).
void BM_PartFactorisation(benchmark::State& state) {
  Moments m(301, static_cast<int>(state.range(0)));
  Eigen::MatrixXd work = m.cyy;
  for (auto _ : state) {
    work = m.cyy;
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(work);
    benchmark::DoNotOptimize(llt.info());
  }
}
BENCHMARK(BM_PartFactorisation)->Arg(50)->Arg(34)->ArgName("visible")->Unit(benchmark::kMicrosecond);

// Gain and update: A^T = Lyy^-1 Cyx, t = Lyy^-1 (y - y^), C+ = C - A A^T with its Cholesky check,
// m+ = m + A t.
void BM_PartGainAndUpdate(benchmark::State& state) {
  Moments m(301, static_cast<int>(state.range(0)));
  const Eigen::LLT<Eigen::MatrixXd> llt(m.cyy);
  const Eigen::MatrixXd prior = 1e4 * Eigen::MatrixXd::Identity(46, 46);
  Eigen::MatrixXd a = m.cyx, posterior = prior;
  Eigen::VectorXd innovation = Eigen::VectorXd::Ones(m.cyx.rows()), mean = Eigen::VectorXd::Zero(46);
  Eigen::LLT<Eigen::MatrixXd> check(46);
  for (auto _ : state) {
    a = m.cyx;
    innovation.setOnes();
    llt.matrixL().solveInPlace(a);
    llt.matrixL().solveInPlace(innovation);
    posterior = prior;
    posterior.selfadjointView<Eigen::Lower>().rankUpdate(a.transpose(), -1.0);
    check.compute(posterior);
    mean.noalias() += a.transpose() * innovation;
    benchmark::DoNotOptimize(mean.data());
  }
}
BENCHMARK(BM_PartGainAndUpdate)->Arg(50)->Arg(34)->ArgName("visible")->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
