/// @file
/// The definitions of <s2kf/io/sample_cache.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/io/sample_cache.hpp>

namespace s2kf {
S2KF_INLINE LcdResult lcd_sample_set(int dimension, int count, const LcdOptions& options,
                                     const SampleCache& cache) {
  // Validate before touching the disk, so bad arguments fail the same way with or without a cache.
  if (dimension < 1 || count < 2 * dimension) return compute_lcd_sample_set(dimension, count, options);
  if (std::optional<LcdResult> loaded = cache.load(dimension, count, options)) return std::move(*loaded);
  LcdResult result = compute_lcd_sample_set(dimension, count, options);
  cache.store(dimension, count, options, result);
  return result;
}

S2KF_INLINE std::optional<LcdResult> SampleCache::load(int dimension, int count,
                                                       const LcdOptions& options) const {
  if (!enabled() || dimension < 1 || count < 1) return std::nullopt;
  const LcdOptions resolved = resolve(dimension, options);
  std::ifstream stream(file_for(dimension, count, options), std::ios::binary);
  if (!stream) return std::nullopt;
  const std::size_t expected =
      header_size + sizeof(double) * static_cast<std::size_t>(dimension) * static_cast<std::size_t>(count) +
      sizeof(std::uint64_t);
  std::vector<unsigned char> bytes;
  bytes.reserve(expected);
  bytes.assign(std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>());
  if (bytes.size() != expected) return std::nullopt;  // truncated or padded
  Reader reader{bytes, 0};
  if (std::memcmp(bytes.data(), magic.data(), magic.size()) != 0) return std::nullopt;
  reader.position = magic.size();
  const std::uint64_t stored_sum = read_u64_at(bytes, expected - sizeof(std::uint64_t));
  if (stored_sum != fnv1a(bytes.data(), expected - sizeof(std::uint64_t))) return std::nullopt;
  if (reader.u32() != format_version) return std::nullopt;
  if (reader.u32() != static_cast<std::uint32_t>(dimension)) return std::nullopt;
  if (reader.u32() != static_cast<std::uint32_t>(count)) return std::nullopt;
  if (reader.f64() != resolved.bmax) return std::nullopt;
  if (reader.u64() != resolved.seed) return std::nullopt;
  if (static_cast<int>(reader.u32()) != resolved.max_iterations) return std::nullopt;
  if (static_cast<int>(reader.u32()) != resolved.history) return std::nullopt;
  if (reader.f64() != resolved.gradient_tolerance) return std::nullopt;
  if (reader.f64() != resolved.relative_tolerance) return std::nullopt;
  LcdResult result;
  result.distance = reader.f64();
  result.iterations = static_cast<int>(reader.u32());
  Eigen::MatrixXd points(dimension, count);
  for (Eigen::Index i = 0; i < points.size(); ++i) points.data()[i] = reader.f64();
  if (!points.allFinite() || !std::isfinite(result.distance)) return std::nullopt;
  result.set = equally_weighted(std::move(points), "lcd");
  result.seconds = 0.0;
  result.cached = true;
  return result;
}

S2KF_INLINE bool SampleCache::store(int dimension, int count, const LcdOptions& options,
                                    const LcdResult& result) const {
  if (!enabled()) return false;
  if (result.set.points.rows() != dimension || result.set.points.cols() != count) return false;
  const LcdOptions resolved = resolve(dimension, options);
  std::vector<unsigned char> bytes(magic.begin(), magic.end());
  put_u32(bytes, format_version);
  put_u32(bytes, static_cast<std::uint32_t>(dimension));
  put_u32(bytes, static_cast<std::uint32_t>(count));
  put_f64(bytes, resolved.bmax);
  put_u64(bytes, resolved.seed);
  put_u32(bytes, static_cast<std::uint32_t>(resolved.max_iterations));
  put_u32(bytes, static_cast<std::uint32_t>(resolved.history));
  put_f64(bytes, resolved.gradient_tolerance);
  put_f64(bytes, resolved.relative_tolerance);
  put_f64(bytes, result.distance);
  put_u32(bytes, static_cast<std::uint32_t>(result.iterations));
  for (Eigen::Index i = 0; i < result.set.points.size(); ++i) put_f64(bytes, result.set.points.data()[i]);
  put_u64(bytes, fnv1a(bytes.data(), bytes.size()));

  std::error_code error;
  std::filesystem::create_directories(directory_, error);
  if (error) return false;
  const std::filesystem::path target = file_for(dimension, count, options);
  const std::filesystem::path temporary = target.string() + ".tmp-" + unique_suffix();
  {
    std::ofstream stream(temporary, std::ios::binary | std::ios::trunc);
    if (!stream) return false;
    stream.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    stream.flush();
    if (!stream) {
      stream.close();
      std::filesystem::remove(temporary, error);
      return false;
    }
  }
  std::filesystem::rename(temporary, target, error);
  if (error) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    return false;
  }
  return true;
}

}  // namespace s2kf
