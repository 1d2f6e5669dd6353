/// @file
/// A disk cache of optimal LCD sample sets: one small checksummed binary file per (N, L, bMax, seed,
/// optimiser settings, format version), written atomically, validated completely before use.
#pragma once

#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/lcd_sample_set.hpp>

#include <Eigen/Core>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <optional>
#include <random>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

namespace s2kf {

/// Where computed sample sets are kept. An empty directory means "no cache": every request
/// computes. Reading never trusts a file: a missing, truncated, corrupt, foreign or mismatching
/// file is treated as absent (and overwritten by the next store).
///
/// File layout (all integers and doubles little-endian, doubles as IEEE-754 bit patterns):
///   magic "S2KFLCD\0" (8 bytes), u32 format version, u32 N, u32 L, f64 bmax, u64 seed,
///   i32 max_iterations, i32 history, f64 gradient_tolerance, f64 relative_tolerance,
///   f64 distance, i32 iterations, N*L f64 points (column-major), u64 FNV-1a checksum of all
///   bytes before it.
class SampleCache {
 public:
  static constexpr std::uint32_t format_version = 1;

  /// A cache in `directory` (created on the first store); an empty path disables caching.
  explicit SampleCache(std::filesystem::path directory = {}) : directory_(std::move(directory)) {}

  /// The cache that computes every time.
  static SampleCache disabled() { return SampleCache{}; }

  /// The directory from the environment, read on every call: $S2KF_CACHE_DIR, else
  /// $XDG_CACHE_HOME/s2kf, else $HOME/.cache/s2kf; disabled when none of these is set.
  static SampleCache default_cache() {
    if (const char* dir = std::getenv("S2KF_CACHE_DIR"); dir != nullptr && *dir != '\0')
      return SampleCache(dir);
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg != '\0')
      return SampleCache(std::filesystem::path(xdg) / "s2kf");
    if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0')
      return SampleCache(std::filesystem::path(home) / ".cache" / "s2kf");
    return disabled();
  }

  bool enabled() const { return !directory_.empty(); }
  const std::filesystem::path& directory() const { return directory_; }

  /// The file that holds (or would hold) the set for these arguments; empty when disabled.
  /// bmax 0 is resolved to default_bmax(dimension) first, so both spellings share a file.
  std::filesystem::path file_for(int dimension, int count, const LcdOptions& options) const {
    if (!enabled()) return {};
    const LcdOptions resolved = resolve(dimension, options);
    char bmax_text[32];
    std::snprintf(bmax_text, sizeof bmax_text, "%.17g", resolved.bmax);
    std::string name = "lcd-n" + std::to_string(dimension) + "-l" + std::to_string(count) + "-bmax" +
                       bmax_text + "-seed" + std::to_string(resolved.seed);
    // The optimiser settings change the result too; the defaults keep the short name.
    const LcdOptions defaults;
    if (resolved.max_iterations != defaults.max_iterations || resolved.history != defaults.history ||
        resolved.gradient_tolerance != defaults.gradient_tolerance ||
        resolved.relative_tolerance != defaults.relative_tolerance) {
      char tag[32];
      std::snprintf(tag, sizeof tag, "-opt%016llx", static_cast<unsigned long long>(settings_hash(resolved)));
      name += tag;
    }
    name += "-v" + std::to_string(format_version) + ".bin";
    return directory_ / name;
  }

  /// The cached set for these arguments, or nothing when there is no valid file. A loaded result
  /// has cached = true and seconds = 0.
  std::optional<LcdResult> load(int dimension, int count, const LcdOptions& options) const;

  /// Writes `result` for these arguments: to a uniquely named temporary file in the cache directory,
  /// then renamed over the final name, so a reader sees either no file or a complete one even with
  /// concurrent writers. Returns false (and leaves nothing behind) when the directory cannot be
  /// created or written; caching is an optimisation, never a reason to fail.
  bool store(int dimension, int count, const LcdOptions& options, const LcdResult& result) const;

 private:
  static constexpr std::array<char, 8> magic{'S', '2', 'K', 'F', 'L', 'C', 'D', '\0'};
  // magic, version, N, L, bmax, seed, max_iterations, history, two tolerances, distance, iterations
  static constexpr std::size_t header_size = 8 + 4 + 4 + 4 + 8 + 8 + 4 + 4 + 8 + 8 + 8 + 4;

  static LcdOptions resolve(int dimension, LcdOptions options) {
    if (options.bmax == 0.0 && dimension >= 1) options.bmax = default_bmax(dimension);
    return options;
  }

  static std::uint64_t fnv1a(const unsigned char* data, std::size_t size) {
    std::uint64_t hash = 14695981039346656037ull;
    for (std::size_t i = 0; i < size; ++i) {
      hash ^= data[i];
      hash *= 1099511628211ull;
    }
    return hash;
  }

  static std::uint64_t settings_hash(const LcdOptions& options) {
    std::vector<unsigned char> bytes;
    put_u32(bytes, static_cast<std::uint32_t>(options.max_iterations));
    put_u32(bytes, static_cast<std::uint32_t>(options.history));
    put_f64(bytes, options.gradient_tolerance);
    put_f64(bytes, options.relative_tolerance);
    return fnv1a(bytes.data(), bytes.size());
  }

  static void put_u64(std::vector<unsigned char>& bytes, std::uint64_t value) {
    for (int i = 0; i < 8; ++i) bytes.push_back(static_cast<unsigned char>(value >> (8 * i)));
  }
  static void put_u32(std::vector<unsigned char>& bytes, std::uint32_t value) {
    for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<unsigned char>(value >> (8 * i)));
  }
  static void put_f64(std::vector<unsigned char>& bytes, double value) {
    std::uint64_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    put_u64(bytes, bits);
  }
  static std::uint64_t read_u64_at(const std::vector<unsigned char>& bytes, std::size_t at) {
    std::uint64_t value = 0;
    for (int i = 0; i < 8; ++i)
      value |= static_cast<std::uint64_t>(bytes[at + static_cast<std::size_t>(i)]) << (8 * i);
    return value;
  }

  struct Reader {
    const std::vector<unsigned char>& bytes;
    std::size_t position;
    std::uint64_t u64() {
      const std::uint64_t value = read_u64_at(bytes, position);
      position += 8;
      return value;
    }
    std::uint32_t u32() {
      std::uint32_t value = 0;
      for (int i = 0; i < 4; ++i) value |= static_cast<std::uint32_t>(bytes[position++]) << (8 * i);
      return value;
    }
    double f64() {
      const std::uint64_t bits = u64();
      double value;
      std::memcpy(&value, &bits, sizeof value);
      return value;
    }
  };

  // Distinct per process and thread without platform calls: a random device draw, the clock and a
  // counter, so two writers never share a temporary file.
  static std::string unique_suffix() {
    static std::atomic<std::uint64_t> counter{0};
    std::random_device device;
    const std::uint64_t mix =
        (static_cast<std::uint64_t>(device()) << 32) ^ device() ^
        static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count()) ^
        (std::hash<std::thread::id>{}(std::this_thread::get_id()) * 31) ^
        (counter.fetch_add(1) * 0x9E3779B97F4A7C15ull);
    char text[20];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(mix));
    return text;
  }

  std::filesystem::path directory_;
};

/// The optimal symmetric LCD sample set for (dimension, count, options): loaded from `cache` when a
/// valid file exists (cached = true, seconds = 0), otherwise computed with compute_lcd_sample_set
/// and stored (a cache that cannot be written is skipped silently). Throws like
/// compute_lcd_sample_set for impossible sizes or options.
LcdResult lcd_sample_set(int dimension, int count, const LcdOptions& options = {},
                         const SampleCache& cache = SampleCache::default_cache());

}  // namespace s2kf

#if !defined(S2KF_COMPILED)
#include <s2kf/io/sample_cache.hxx>
#endif
