// Optimal LCD sample sets: the full computation (no cache) for the seed paper's and the default
// size of the 46-dimensional tracking state, and one evaluation of the objective with its gradient.
#include <s2kf/core/lcd_sample_set.hpp>

#include <benchmark/benchmark.h>

namespace {

void BM_ComputeLcdSampleSet(benchmark::State& state) {
  const int dimension = static_cast<int>(state.range(0));
  const int count = static_cast<int>(state.range(1));
  s2kf::LcdResult result;
  for (auto _ : state) {
    result = s2kf::compute_lcd_sample_set(dimension, count);
    benchmark::DoNotOptimize(result.set.points.data());
  }
  state.counters["distance"] = result.distance;
  state.counters["iterations"] = result.iterations;
}
BENCHMARK(BM_ComputeLcdSampleSet)
    ->Args({46, 301})
    ->Args({46, 461})
    ->Args({3, 31})
    ->Args({10, 101})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// One value + gradient of the symmetric objective, as the optimiser calls it, at a random start.
void BM_SymmetricObjectiveAndGradient(benchmark::State& state) {
  const int dimension = static_cast<int>(state.range(0));
  const int count = static_cast<int>(state.range(1));
  s2kf::LcdObjective objective(dimension, s2kf::default_bmax(dimension));
  s2kf::detail::BoxMuller normal(1);
  Eigen::MatrixXd half(dimension, count / 2), gradient(dimension, count / 2);
  for (Eigen::Index i = 0; i < half.size(); ++i) half.data()[i] = normal();
  for (auto _ : state) benchmark::DoNotOptimize(objective.evaluate_symmetric(half, count % 2 == 1, gradient));
}
BENCHMARK(BM_SymmetricObjectiveAndGradient)->Args({46, 301})->Args({46, 461})->Unit(benchmark::kMicrosecond);

// The same through the moment-correcting (whitening) wrapper that compute_lcd_sample_set minimises.
void BM_WhitenedObjectiveAndGradient(benchmark::State& state) {
  const int dimension = static_cast<int>(state.range(0));
  const int count = static_cast<int>(state.range(1));
  s2kf::LcdObjective objective(dimension, s2kf::default_bmax(dimension));
  s2kf::detail::WhitenedSymmetricObjective whitened(objective, count / 2, count % 2 == 1);
  s2kf::detail::BoxMuller normal(1);
  Eigen::VectorXd x(dimension * (count / 2)), gradient(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = normal();
  for (auto _ : state) benchmark::DoNotOptimize(whitened(x, gradient));
}
BENCHMARK(BM_WhitenedObjectiveAndGradient)->Args({46, 301})->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
