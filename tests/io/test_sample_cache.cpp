// The disk cache of LCD sample sets: bit-identical round trip, and every kind of bad file is
// recomputed and rewritten, never used.
#include <s2kf/io/sample_cache.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;
using s2kf::LcdOptions;
using s2kf::SampleCache;

// A fresh directory per test, so tests never see each other's files.
fs::path cache_scratch(const std::string& name) {
  const fs::path dir = fs::path(s2kf::test_support::tmp_dir()) / "sample_cache" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<char> read_bytes(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& path, const std::vector<char>& bytes) {
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(SampleCache, RoundTripIsBitIdentical) {
  const SampleCache cache(cache_scratch("round_trip"));
  const auto computed = s2kf::lcd_sample_set(3, 15, {}, cache);
  EXPECT_FALSE(computed.cached);
  EXPECT_GT(computed.seconds, 0.0);
  const fs::path file = cache.file_for(3, 15, {});
  ASSERT_TRUE(fs::exists(file)) << file;
  const auto loaded = s2kf::lcd_sample_set(3, 15, {}, cache);
  EXPECT_TRUE(loaded.cached);
  EXPECT_EQ(loaded.seconds, 0.0);
  EXPECT_EQ(loaded.set.points, computed.set.points);
  EXPECT_EQ(loaded.set.weights, computed.set.weights);
  EXPECT_EQ(loaded.set.kind, "lcd");
  EXPECT_EQ(loaded.distance, computed.distance);
  EXPECT_EQ(loaded.iterations, computed.iterations);
  // No temporary files are left behind.
  int files = 0;
  for (const auto& entry : fs::directory_iterator(cache.directory())) {
    ++files;
    EXPECT_EQ(entry.path(), file);
  }
  EXPECT_EQ(files, 1);
}

TEST(SampleCache, KeyCoversEveryArgumentThatChangesTheSet) {
  const SampleCache cache(cache_scratch("keys"));
  LcdOptions options;
  const fs::path base = cache.file_for(3, 15, options);
  EXPECT_NE(base, cache.file_for(3, 17, options));
  EXPECT_NE(base, cache.file_for(4, 15, options));
  options.seed = 2;
  EXPECT_NE(base, cache.file_for(3, 15, options));
  options = {};
  options.bmax = 7.5;
  EXPECT_NE(base, cache.file_for(3, 15, options));
  options = {};
  options.relative_tolerance = 1e-9;
  EXPECT_NE(base, cache.file_for(3, 15, options));
  options = {};
  options.bmax = s2kf::default_bmax(3);  // the default spelled out shares the file
  EXPECT_EQ(base, cache.file_for(3, 15, options));
  // A different seed is computed, not served from the other seed's file.
  s2kf::lcd_sample_set(3, 15, {}, cache);
  options = {};
  options.seed = 2;
  EXPECT_FALSE(s2kf::lcd_sample_set(3, 15, options, cache).cached);
  EXPECT_TRUE(s2kf::lcd_sample_set(3, 15, options, cache).cached);
}

// Damages the cache file with `damage`, then checks that the next call recomputes (the same set,
// since the computation is deterministic), rewrites a valid file, and the call after loads it.
void expect_recomputed_after(const std::string& name, const std::function<void(const fs::path&)>& damage) {
  const SampleCache cache(cache_scratch(name));
  const auto original = s2kf::lcd_sample_set(2, 9, {}, cache);
  const fs::path file = cache.file_for(2, 9, {});
  const std::vector<char> good = read_bytes(file);
  damage(file);
  const auto again = s2kf::lcd_sample_set(2, 9, {}, cache);
  EXPECT_FALSE(again.cached) << name;
  EXPECT_EQ(again.set.points, original.set.points) << name;
  EXPECT_EQ(read_bytes(file), good) << name << ": the file was not rewritten";
  EXPECT_TRUE(s2kf::lcd_sample_set(2, 9, {}, cache).cached) << name;
}

TEST(SampleCache, TruncatedFileIsRecomputed) {
  expect_recomputed_after("truncated", [](const fs::path& file) {
    std::vector<char> bytes = read_bytes(file);
    bytes.resize(bytes.size() - 13);
    write_bytes(file, bytes);
  });
  expect_recomputed_after("empty", [](const fs::path& file) { write_bytes(file, {}); });
}

TEST(SampleCache, CorruptFileIsRecomputed) {
  expect_recomputed_after("corrupt_point", [](const fs::path& file) {
    std::vector<char> bytes = read_bytes(file);
    bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x10);  // one bit of a point
    write_bytes(file, bytes);
  });
  expect_recomputed_after("corrupt_checksum", [](const fs::path& file) {
    std::vector<char> bytes = read_bytes(file);
    bytes.back() = static_cast<char>(bytes.back() ^ 0x01);
    write_bytes(file, bytes);
  });
  expect_recomputed_after("padded", [](const fs::path& file) {
    std::vector<char> bytes = read_bytes(file);
    bytes.push_back('x');
    write_bytes(file, bytes);
  });
}

TEST(SampleCache, ForeignFileIsRecomputed) {
  expect_recomputed_after("text",
                          [](const fs::path& file) { std::ofstream(file) << "dimension,count\n2,9\n"; });
  // A valid cache file, but of another set, under this set's name.
  expect_recomputed_after("other_set", [](const fs::path& file) {
    const SampleCache other(file.parent_path() / "other");
    s2kf::lcd_sample_set(2, 10, {}, other);
    fs::copy_file(other.file_for(2, 10, {}), file, fs::copy_options::overwrite_existing);
  });
  expect_recomputed_after("missing", [](const fs::path& file) { fs::remove(file); });
}

TEST(SampleCache, DisabledOrUnwritableCacheStillComputes) {
  const auto disabled = s2kf::lcd_sample_set(2, 9, {}, SampleCache::disabled());
  EXPECT_FALSE(disabled.cached);
  EXPECT_FALSE(SampleCache::disabled().enabled());
  EXPECT_TRUE(SampleCache::disabled().file_for(2, 9, {}).empty());
  // A cache "directory" below a regular file can never be created.
  const fs::path dir = cache_scratch("unwritable");
  std::ofstream(dir / "a_file") << "x";
  const SampleCache impossible(dir / "a_file" / "cache");
  const auto computed = s2kf::lcd_sample_set(2, 9, {}, impossible);
  EXPECT_FALSE(computed.cached);
  EXPECT_EQ(computed.set.points.cols(), 9);
  EXPECT_FALSE(s2kf::lcd_sample_set(2, 9, {}, impossible).cached);
}

TEST(SampleCache, BadArgumentsFailWithOrWithoutACache) {
  const SampleCache cache(cache_scratch("bad"));
  EXPECT_THROW(s2kf::lcd_sample_set(3, 5, {}, cache), s2kf::DimensionError);
  EXPECT_THROW(s2kf::lcd_sample_set(0, 5, {}, cache), s2kf::DimensionError);
  EXPECT_TRUE(fs::is_empty(cache.directory()));
}

TEST(SampleCache, DefaultDirectoryFollowsTheEnvironment) {
  const char* saved = std::getenv("S2KF_CACHE_DIR");
  const std::string saved_value = saved ? saved : "";
  const fs::path dir = cache_scratch("environment");
  setenv("S2KF_CACHE_DIR", dir.c_str(), 1);
  EXPECT_EQ(SampleCache::default_cache().directory(), dir);
  unsetenv("S2KF_CACHE_DIR");
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  const char* home = std::getenv("HOME");
  if (xdg != nullptr && *xdg != '\0') {
    EXPECT_EQ(SampleCache::default_cache().directory(), fs::path(xdg) / "s2kf");
  } else if (home != nullptr && *home != '\0') {
    EXPECT_EQ(SampleCache::default_cache().directory(), fs::path(home) / ".cache" / "s2kf");
  }
  if (saved) setenv("S2KF_CACHE_DIR", saved_value.c_str(), 1);
}

TEST(SampleCache, ConcurrentWritersLeaveOneValidFile) {
  const SampleCache cache(cache_scratch("concurrent"));
  const auto reference = s2kf::compute_lcd_sample_set(3, 13);
  std::vector<std::thread> writers;
  for (int t = 0; t < 4; ++t)
    writers.emplace_back([&] {
      for (int i = 0; i < 10; ++i) cache.store(3, 13, {}, reference);
    });
  for (auto& writer : writers) writer.join();
  const auto loaded = cache.load(3, 13, {});
  ASSERT_TRUE(loaded.has_value());
  EXPECT_EQ(loaded->set.points, reference.set.points);
  int files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(cache.directory())) ++files;
  EXPECT_EQ(files, 1);
}

}  // namespace
