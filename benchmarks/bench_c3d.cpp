// C3D throughput: reading a large float file from the page cache (whole-file and streaming) and
// writing it. The file, 100k frames x 50 markers (80 MB), is written once by the writer to /tmp.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <random>
#include <string>

#include "s2kf/io/c3d_reader.hpp"
#include "s2kf/io/c3d_writer.hpp"

namespace {

constexpr int kPoints = 50;
constexpr int kFrames = 100000;

struct Data {
  std::vector<std::string> labels;
  Eigen::MatrixXd positions;
  Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic> visible;
};

const Data& data() {
  static const Data d = [] {
    Data d;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> coordinate(-2000.0, 2000.0);
    std::bernoulli_distribution gap(0.05);
    for (int p = 0; p < kPoints; ++p) d.labels.push_back("Subject:M" + std::to_string(p));
    d.positions.resize(3 * kPoints, kFrames);
    d.visible.resize(kPoints, kFrames);
    for (Eigen::Index i = 0; i < d.positions.size(); ++i) d.positions.data()[i] = coordinate(rng);
    for (Eigen::Index i = 0; i < d.visible.size(); ++i) d.visible.data()[i] = !gap(rng);
    return d;
  }();
  return d;
}

const std::string& large_file() {
  static const std::string path = [] {
    const std::string p = "/tmp/s2kf_bench_c3d_100k_x_50.c3d";
    s2kf::c3d::write_c3d(p, data().labels, 120.0, data().positions, data().visible);
    return p;
  }();
  return path;
}

void BM_C3dReadWholeFile(benchmark::State& state) {
  const std::string& path = large_file();
  const auto bytes = static_cast<std::int64_t>(std::filesystem::file_size(path));
  for (auto _ : state) {
    const s2kf::c3d::Recording r = s2kf::c3d::read_c3d(path);
    benchmark::DoNotOptimize(r.positions.data());
  }
  state.SetBytesProcessed(state.iterations() * bytes);
}
BENCHMARK(BM_C3dReadWholeFile)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_C3dReadStreaming(benchmark::State& state) {
  const std::string& path = large_file();
  const auto bytes = static_cast<std::int64_t>(std::filesystem::file_size(path));
  for (auto _ : state) {
    s2kf::c3d::C3dReader reader(path);
    s2kf::MarkerFrame frame;
    double sum = 0.0;
    while (reader.read_frame(frame)) sum += frame.positions(0, 0);
    benchmark::DoNotOptimize(sum);
  }
  state.SetBytesProcessed(state.iterations() * bytes);
}
BENCHMARK(BM_C3dReadStreaming)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_C3dWrite(benchmark::State& state) {
  const Data& d = data();
  const std::string path = "/tmp/s2kf_bench_c3d_write.c3d";
  for (auto _ : state) s2kf::c3d::write_c3d(path, d.labels, 120.0, d.positions, d.visible);
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(std::filesystem::file_size(path)));
}
BENCHMARK(BM_C3dWrite)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
