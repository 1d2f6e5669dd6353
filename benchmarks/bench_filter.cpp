// The S2KF measurement update of a linear model at the tracking size (46 states, 150 measurements)
// for the UKF-sized set (93 samples) and LCD sets of 301 and 461 samples.
//   build/benchmarks/bench_filter --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <s2kf/core/sample_cache.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>

#include <benchmark/benchmark.h>

#include <random>

namespace {

constexpr int kStates = 46;
constexpr int kMeasurements = 150;

s2kf::SampleSet sample_set(int count) {
  return count == 2 * kStates + 1 ? s2kf::ukf_sample_set(kStates) : s2kf::lcd_sample_set(kStates, count).set;
}

void BM_LinearUpdate(benchmark::State& state) {
  const int count = static_cast<int>(state.range(0));
  s2kf::S2kf filter(sample_set(count));
  std::mt19937_64 rng(1);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd h(kMeasurements, kStates), a(kStates, kStates);
  for (int i = 0; i < h.size(); ++i) h.data()[i] = normal(rng);
  for (int i = 0; i < a.size(); ++i) a.data()[i] = normal(rng);
  const Eigen::MatrixXd prior = a * a.transpose() + Eigen::MatrixXd::Identity(kStates, kStates);
  const Eigen::MatrixXd r = 100.0 * Eigen::MatrixXd::Identity(kMeasurements, kMeasurements);
  Eigen::VectorXd y(kMeasurements);
  for (int i = 0; i < y.size(); ++i) y(i) = normal(rng);
  auto model = [&](const Eigen::MatrixXd& x, Eigen::MatrixXd& out) { out.noalias() = h * x; };
  const s2kf::ObservedMask observed = s2kf::ObservedMask::Constant(kMeasurements, true);
  s2kf::GaussianXd estimate(Eigen::VectorXd::Zero(kStates), prior);
  for (auto _ : state) {
    estimate.covariance = prior;
    const auto result = filter.update(estimate, model, y, r, observed);
    benchmark::DoNotOptimize(result.nis);
  }
  state.counters["samples"] = count;
}
BENCHMARK(BM_LinearUpdate)->Arg(93)->Arg(301)->Arg(461)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
