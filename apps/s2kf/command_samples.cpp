// `s2kf samples`: computes (or loads from the disk cache) an optimal LCD sample set of N(0, I),
// prints a summary or one JSON object, and optionally writes the points as CSV.
#include "command.hpp"

#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/sample_cache.hpp>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <string>

namespace {

struct SamplesArguments {
  int dimension = 0;
  int count = 0;  // 0: default_sample_count(dimension)
  double bmax = 0.0;
  std::uint64_t seed = 1;
  std::string out;
  bool json = false;
  std::string cache_dir;
  bool no_cache = false;
};

void run_samples(const SamplesArguments& args) {
  using s2kf::cli::UserError;
  if (args.dimension < 1) throw UserError("--dim must be at least 1 (the dimension of the state)");
  const int count = args.count > 0 ? args.count : s2kf::default_sample_count(args.dimension);
  if (args.count < 0) throw UserError("--count must be positive");
  if (count < 2 * args.dimension)
    throw UserError("a symmetric sample set in " + std::to_string(args.dimension) +
                    " dimensions needs at least " + std::to_string(2 * args.dimension) +
                    " samples; --count " + std::to_string(count) + " is too small");
  if (args.bmax < 0.0) throw UserError("--bmax must be positive (leave it out for the default)");
  if (!args.out.empty()) {
    // Fail before a long computation, not after it.
    const std::filesystem::path parent = std::filesystem::absolute(args.out).parent_path();
    if (!std::filesystem::is_directory(parent))
      throw UserError("cannot write " + args.out + ": the directory " + parent.string() + " does not exist");
  }

  s2kf::LcdOptions options;
  options.bmax = args.bmax;
  options.seed = args.seed;
  const s2kf::SampleCache cache = args.no_cache            ? s2kf::SampleCache::disabled()
                                  : args.cache_dir.empty() ? s2kf::SampleCache::default_cache()
                                                           : s2kf::SampleCache(args.cache_dir);
  s2kf::LcdResult result;
  try {
    result = s2kf::lcd_sample_set(args.dimension, count, options, cache);
  } catch (const std::invalid_argument& error) {
    throw UserError(error.what());
  }
  const double bmax = args.bmax > 0.0 ? args.bmax : s2kf::default_bmax(args.dimension);
  const std::filesystem::path cache_file = cache.file_for(args.dimension, count, options);
  const bool in_cache = !cache_file.empty() && std::filesystem::exists(cache_file);

  if (!args.out.empty()) {
    try {
      s2kf::io::write_file_atomically(args.out, [&](std::ostream& stream) {
        stream << std::setprecision(std::numeric_limits<double>::max_digits10);
        const Eigen::MatrixXd& z = result.set.points;
        for (Eigen::Index j = 0; j < z.cols(); ++j) {
          for (Eigen::Index i = 0; i < z.rows(); ++i) stream << (i ? "," : "") << z(i, j);
          stream << "\n";
        }
      });
    } catch (const std::runtime_error& error) {
      throw UserError(error.what());
    }
  }

  if (args.json) {
    nlohmann::ordered_json summary;
    summary["dimension"] = args.dimension;
    summary["count"] = count;
    summary["bmax"] = bmax;
    summary["distance"] = result.distance;
    summary["iterations"] = result.iterations;
    summary["seconds"] = result.cached ? 0.0 : result.seconds;
    summary["cached"] = result.cached;
    std::cout << summary.dump() << "\n";
    return;
  }
  std::cout << "dimension   " << args.dimension << "\n"
            << "count       " << count << "\n"
            << "bmax        " << bmax << "\n"
            << "distance    " << std::setprecision(8) << result.distance << "\n"
            << "iterations  " << result.iterations << "\n"
            << "seconds     " << std::setprecision(4) << result.seconds << "\n"
            << "cached      " << (result.cached ? "yes (loaded)" : "no (computed)") << "\n"
            << "cache file  "
            << (in_cache ? cache_file.string() : std::string("none (caching off or not writable)")) << "\n";
  if (!args.out.empty()) std::cout << "points      " << args.out << " (one sample per row)\n";
}

const s2kf::cli::RegisterCommand register_samples{
    "samples", "Compute (or load from the cache) an optimal LCD sample set of the standard normal",
    [](CLI::App& app) {
      auto args = std::make_shared<SamplesArguments>();
      app.add_option("--dim", args->dimension, "Dimension N of the state")->required();
      app.add_option("--count", args->count,
                     "Number of samples L (at least 2N; default 10 N rounded up to odd)");
      app.add_option("--bmax", args->bmax, "Largest kernel width of the LCD distance (default by dimension)");
      app.add_option("--seed", args->seed, "Seed of the random start (default 1)");
      app.add_option("--out", args->out, "Write the points as CSV, one sample per row, N columns");
      app.add_flag("--json", args->json, "Print one JSON object instead of the summary");
      app.add_option("--cache-dir", args->cache_dir,
                     "Cache directory (default $S2KF_CACHE_DIR, $XDG_CACHE_HOME/s2kf or ~/.cache/s2kf)");
      app.add_flag("--no-cache", args->no_cache, "Neither read nor write the cache");
      app.callback([args] { run_samples(*args); });
    }};

}  // namespace
