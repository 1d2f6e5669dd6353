// The S2KF measurement update of a linear model at the tracking size (46 states, 150 measurements)
// for the UKF-sized set (93 samples) and LCD sets of 301 and 461 samples; and the gain's
// factorisation at the tracker's sizes (a leg's 24 components, the pelvis's 21, the 46 x 46
// information matrix, the upper body's 81, the whole 150) with a border of 47 rows (46 states and
// the innovation): BorderedCholesky against Eigen's LLT and triangular solve; and the moments'
// single-precision products at the step's sizes (args: rows, columns, samples): the lower half of
// D D^T and D Z^T by the register tiles (product_tiles.hpp) against Eigen's products.
//   build/benchmarks/bench_filter --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <s2kf/core/bordered_cholesky.hpp>
#include <s2kf/core/product_tiles.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>
#include <s2kf/io/sample_cache.hpp>

#include <benchmark/benchmark.h>
#include <Eigen/Cholesky>

#include <algorithm>
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

// A well-conditioned symmetric positive-definite matrix and a random border, as in the gain.
struct Panel {
  Eigen::MatrixXd matrix, border;
  explicit Panel(Eigen::Index size) {
    std::mt19937_64 rng(2);
    std::normal_distribution<double> normal;
    Eigen::MatrixXd a(size, size + 10);
    for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = normal(rng);
    matrix = a * a.transpose() + static_cast<double>(size) * Eigen::MatrixXd::Identity(size, size);
    border.resize(kStates + 1, size);
    for (Eigen::Index i = 0; i < border.size(); ++i) border.data()[i] = normal(rng);
  }
};

// Both benchmarks copy the inputs in every iteration, as the gain does.
void BM_BorderedCholesky(benchmark::State& state) {
  const Eigen::Index size = state.range(0);
  const Panel input(size);
  s2kf::BorderedCholesky bordered;
  bordered.resize(size, input.border.rows());
  for (auto _ : state) {
    auto panel = bordered.panel();
    panel.topRows(size).triangularView<Eigen::Lower>() = input.matrix;
    panel.bottomRows(input.border.rows()) = input.border;
    const bool positive = bordered.factorise();
    benchmark::DoNotOptimize(positive);
  }
}
BENCHMARK(BM_BorderedCholesky)->Arg(21)->Arg(24)->Arg(46)->Arg(81)->Arg(150)->Unit(benchmark::kMicrosecond);

void BM_EigenCholeskyAndSolve(benchmark::State& state) {
  const Eigen::Index size = state.range(0);
  const Panel input(size);
  Eigen::MatrixXd matrix(size, size), border(input.border.rows(), size);
  for (auto _ : state) {
    matrix.triangularView<Eigen::Lower>() = input.matrix;
    border = input.border;
    const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(matrix);
    llt.matrixU().solveInPlace<Eigen::OnTheRight>(border);
    benchmark::DoNotOptimize(border.data());
  }
}
BENCHMARK(BM_EigenCholeskyAndSolve)
    ->Arg(21)
    ->Arg(24)
    ->Arg(46)
    ->Arg(81)
    ->Arg(150)
    ->Unit(benchmark::kMicrosecond);

// The moments' products. Args: rows of D (150 coordinates, 81 the upper body's), columns of the
// other factor (0: D D^T, lower half; else the rows of Z: 46 states), samples.
struct ProductInput {
  Eigen::MatrixXf left, right, target;
  explicit ProductInput(const benchmark::State& state)
      : left(Eigen::MatrixXf::Random(state.range(0), state.range(2))),
        right(Eigen::MatrixXf::Random(state.range(1), state.range(2))),
        target(state.range(0), state.range(1) == 0 ? state.range(0) : state.range(1)) {}
};

void BM_ProductTiles(benchmark::State& state) {
  ProductInput p(state);
  for (auto _ : state) {
    p.target.setZero();
    if (p.right.rows() == 0)
      s2kf::add_self_product_lower(p.target, p.left);
    else
      s2kf::add_product_transposed(p.target, p.left, p.right);
    benchmark::DoNotOptimize(p.target.data());
  }
}

// Eigen's products as the filter used them before the tiles: the rank update and the general
// product over chunks of 96 samples (their packing buffers then stay on the stack).
void BM_EigenProducts(benchmark::State& state) {
  ProductInput p(state);
  constexpr Eigen::Index chunk = 96;
  for (auto _ : state) {
    p.target.setZero();
    for (Eigen::Index k = 0; k < p.left.cols(); k += chunk) {
      const Eigen::Index c = std::min(chunk, p.left.cols() - k);
      if (p.right.rows() == 0)
        p.target.selfadjointView<Eigen::Lower>().rankUpdate(p.left.middleCols(k, c));
      else
        p.target.noalias() += p.left.middleCols(k, c) * p.right.middleCols(k, c).transpose();
    }
    benchmark::DoNotOptimize(p.target.data());
  }
}

void product_args(benchmark::internal::Benchmark* b) {
  b->Args({150, 0, 301})->Args({150, 0, 93})->Args({81, 0, 301})->Args({150, 46, 150})->Args({46, 150, 150});
  b->ArgNames({"rows", "columns", "samples"})->Unit(benchmark::kMicrosecond);
}
BENCHMARK(BM_ProductTiles)->Apply(product_args);
BENCHMARK(BM_EigenProducts)->Apply(product_args);

}  // namespace

BENCHMARK_MAIN();
