// The parts of the whole-body tracking step's filter update on the converged state of
// data/handstand.c3d: the update without forward kinematics, the moments, the factorisation and
// the gain (bench_track times the whole step, the forward kinematics and the floor).
// docs/benchmarks.md has the numbers and the commands.
#include "track_scenario.hpp"

#include <benchmark/benchmark.h>

namespace {

using namespace track_bench;

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
