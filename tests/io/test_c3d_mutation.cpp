// Thousands of corrupted variants of the real C3D files (seeded, so every run tests the same
// ones): the reader must either throw C3dError or return a consistent result, never crash, hang,
// allocate without bound or throw anything else. Runs under ASan/UBSan in CI. C3dFuzz goes on
// from there with a new seed each run for a bounded time: stacked libFuzzer-style mutations of
// every bundled file, the mutation loop CI runs where no libFuzzer is built.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "s2kf/body/label_text.hpp"
#include "s2kf/io/c3d_reader.hpp"

namespace {

using s2kf::c3d::C3dError;
using s2kf::c3d::C3dReader;
using s2kf::c3d::Frame;

std::string load(const std::string& file) {
  std::ifstream in(std::string(S2KF_C3D_DATA_DIR) + "/" + file, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

struct Outcome {
  int errors = 0;
  int results = 0;
};

/// Reads the header, parameters and the first frames of `bytes`; checks the result is consistent.
void read_variant(const std::string& bytes, Outcome& outcome) {
  try {
    C3dReader reader(std::make_unique<std::istringstream>(bytes), "variant.c3d");
    const auto& info = reader.info();
    const auto size = static_cast<std::int64_t>(bytes.size());
    ASSERT_GE(info.frame_count, 0);
    ASSERT_LE(info.data_offset + info.frame_count * info.frame_bytes, size);
    ASSERT_EQ(info.labels.size(), static_cast<std::size_t>(info.point_count));
    // Every text the reader hands on is UTF-8, whatever bytes the file holds (JSON and CSV
    // outputs carry it).
    for (const auto& label : info.labels)
      ASSERT_TRUE(s2kf::is_utf8(label.raw) && s2kf::is_utf8(label.name) && s2kf::is_utf8(label.subject))
          << label.raw;
    ASSERT_TRUE(s2kf::is_utf8(info.units)) << info.units;
    for (const std::string& text : info.descriptions) ASSERT_TRUE(s2kf::is_utf8(text)) << text;
    for (const std::string& text : info.warnings) ASSERT_TRUE(s2kf::is_utf8(text)) << text;
    Frame frame;
    for (int f = 0; f < 6 && reader.read_frame(frame); ++f)
      for (Eigen::Index p = 0; p < frame.positions.cols(); ++p) {
        if (frame.visible(p)) {
          ASSERT_TRUE(frame.positions.col(p).allFinite());
        } else {
          ASSERT_TRUE(frame.positions.col(p).array().isNaN().all());
        }
      }
    ++outcome.results;
  } catch (const C3dError& error) {
    ASSERT_GT(std::string(error.what()).size(), 12u);
    ++outcome.errors;
  }
}

/// The file cut to its header, parameters and a few frames, so that each variant is cheap.
std::string shortened(const std::string& bytes) {
  try {
    C3dReader reader(std::make_unique<std::istringstream>(bytes), "original");
    const auto keep = reader.info().data_offset + 4 * reader.info().frame_bytes;
    return bytes.substr(0, static_cast<std::size_t>(std::min<std::int64_t>(keep, bytes.size())));
  } catch (const C3dError&) {
    return bytes;
  }
}

class C3dMutation : public ::testing::TestWithParam<std::string> {};

TEST_P(C3dMutation, CorruptedVariantsGiveAnErrorOrAConsistentResult) {
  const std::string original = shortened(load(GetParam()));
  ASSERT_FALSE(original.empty());
  std::mt19937 rng(20240531u + static_cast<unsigned>(GetParam().size()));
  const auto below = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
  const std::size_t parameter_start = 512 * (static_cast<unsigned char>(original[0]) - std::size_t(1));
  const std::size_t parameter_end = std::min(original.size(), parameter_start + 4096);
  Outcome outcome;

  // Truncations at many offsets, dense in the header and parameter section.
  for (std::size_t cut = 0; cut < original.size(); cut += (cut < parameter_end ? 53 : 509))
    read_variant(original.substr(0, cut), outcome);

  for (int trial = 0; trial < 220; ++trial) {
    std::string v = original;
    switch (trial % 5) {
      case 0:  // flipped bits in the header
        for (int k = 0; k < 3; ++k)
          v[below(std::min<std::size_t>(512, v.size()))] ^= static_cast<char>(1 << below(8));
        break;
      case 1:  // random bytes in the parameter section
        if (parameter_end > parameter_start + 4)
          for (int k = 0; k < 4; ++k)
            v[parameter_start + 4 + below(parameter_end - parameter_start - 4)] =
                static_cast<char>(below(256));
        break;
      case 2: {  // absurd header counts and offsets
        static const std::uint16_t absurd[] = {0, 1, 2, 0x7FFF, 0x8000, 0xFFFF, 255, 256};
        const std::size_t word = 2 * (1 + below(10));  // words 2..11
        const std::uint16_t value = absurd[below(8)];
        v[word] = static_cast<char>(value & 0xFF);
        v[word + 1] = static_cast<char>(value >> 8);
        break;
      }
      case 3:  // huge dimensions and lengths: 0xFF / 0x80 / 0x7F at random parameter bytes
        if (parameter_end > parameter_start + 4)
          for (int k = 0; k < 6; ++k) {
            static const char extreme[] = {'\xFF', '\x80', '\x7F', '\x00'};
            v[parameter_start + 4 + below(parameter_end - parameter_start - 4)] = extreme[below(4)];
          }
        break;
      case 4:  // processor byte and parameter block pointer
        v[below(2) == 0 ? 0 : std::min(v.size() - 1, parameter_start + 3)] = static_cast<char>(below(256));
        break;
    }
    read_variant(v, outcome);
    if (trial % 10 == 0) read_variant(v.substr(0, below(v.size())), outcome);
  }
  EXPECT_GT(outcome.results, 0);
  EXPECT_GT(outcome.errors, 0);
  RecordProperty("results", outcome.results);
  RecordProperty("errors", outcome.errors);
}

INSTANTIATE_TEST_SUITE_P(RealFiles, C3dMutation,
                         ::testing::Values("85_02.c3d", "AlbertoINT.c3d", "BTS.c3d", "Dance.c3d",
                                           "Eb015pi.c3d", "Eb015sr.c3d", "Eb015vr.c3d",
                                           "HDM_mm_01-02_03_120.c3d", "MACsample.c3d", "MotionMonitorC3D.c3d",
                                           "Optotrak.c3d", "PiG_Motion-FlatFoot-One.c3d", "Vicon.c3d",
                                           "Walk1.c3d", "bad_parameter_section.c3d", "phasespace_sample.c3d",
                                           "test1.c3d"),
                         [](const auto& info) {
                           std::string name = info.param.substr(0, info.param.find('.'));
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

/// A number from the environment, or `fallback` when the variable is unset or not a number.
double environment_number(const char* name, double fallback) {
  const char* text = std::getenv(name);
  char* end = nullptr;
  const double value = text ? std::strtod(text, &end) : fallback;
  return text && end != text ? value : fallback;
}

/// One to eight stacked mutations of `v`, libFuzzer's kinds: bit flips, random and boundary bytes,
/// boundary 16/32-bit words and floats (NaN, infinity, 1e30, 1e-40, 0, -1), erased, inserted and
/// repeated chunks, a cut, and a splice from another file. Two in three land in the header and
/// parameter blocks, where the reader decides what the rest of the file means.
std::string mutate(std::string v, const std::string& other, std::mt19937& rng) {
  const auto below = [&](std::size_t n) {
    return n == 0 ? std::size_t(0) : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  };
  const auto offset = [&](std::size_t width) {  // v shrinks and grows as mutations stack up
    const std::size_t head = std::min<std::size_t>(v.size(), 512 * 12);
    const std::size_t range = below(3) < 2 ? head : v.size();
    return range > width ? below(range - width + 1) : std::size_t(0);
  };
  static const std::uint32_t words[] = {0,      1,      0x7F,   0x80,       0xFF,
                                        0x7FFF, 0x8000, 0xFFFF, 0x7FFFFFFF, 0xFFFFFFFF};
  static const float floats[] = {0.0f,
                                 -1.0f,
                                 1e30f,
                                 1e-40f,
                                 -0.0f,
                                 std::numeric_limits<float>::quiet_NaN(),
                                 std::numeric_limits<float>::infinity()};
  for (std::size_t n = 1 + below(8); n > 0 && !v.empty(); --n) {
    switch (below(9)) {
      case 0:
        v[offset(1)] ^= static_cast<char>(1 << below(8));
        break;
      case 1:
        v[offset(1)] = static_cast<char>(below(256));
        break;
      case 2:
        v[offset(1)] = static_cast<char>(words[below(5)]);
        break;
      case 3:
        if (v.size() >= 2) {
          const std::uint32_t w = words[below(8)];
          const std::size_t at = offset(2);
          v[at] = static_cast<char>(w & 0xFF), v[at + 1] = static_cast<char>((w >> 8) & 0xFF);
        }
        break;
      case 4:
        if (v.size() >= 4) {
          const float f = floats[below(7)];
          std::uint32_t bits = below(2) ? words[below(10)] : 0;
          if (bits == 0) std::memcpy(&bits, &f, 4);
          std::memcpy(&v[offset(4)], &bits, 4);
        }
        break;
      case 5: {
        const std::size_t at = offset(1);
        v.erase(at, 1 + below(std::min<std::size_t>(64, v.size() - at)));
        break;
      }
      case 6: {
        std::string bytes(1 + below(32), '\0');
        for (char& c : bytes) c = static_cast<char>(below(256));
        v.insert(offset(0), bytes);
        break;
      }
      case 7: {
        const std::size_t at = offset(1);
        v.insert(offset(0), v.substr(at, 1 + below(std::min<std::size_t>(128, v.size() - at))));
        break;
      }
      case 8:
        if (below(2) && !other.empty()) {
          const std::size_t at = offset(1), from = below(other.size());
          v.replace(at, std::min<std::size_t>(256, v.size() - at), other.substr(from, 1 + below(256)));
        } else {
          v.resize(below(v.size()));
        }
        break;
    }
  }
  return v;
}

TEST(C3dFuzz, RandomMutationsForABoundedTimeGiveAnErrorOrAConsistentResult) {
  // S2KF_FUZZ_SECONDS (default 20) bounds the run; S2KF_FUZZ_SEED repeats one (printed on failure).
  const double seconds = environment_number("S2KF_FUZZ_SECONDS", 20.0);
  const auto seed = static_cast<unsigned>(environment_number("S2KF_FUZZ_SEED", std::random_device{}()));
  SCOPED_TRACE("S2KF_FUZZ_SEED=" + std::to_string(seed));
  RecordProperty("seed", static_cast<int>(seed));
  std::vector<std::string> corpus;
  for (const auto& folder : {std::string(S2KF_C3D_DATA_DIR), std::string(S2KF_DATA_DIR)})
    for (const auto& entry : std::filesystem::directory_iterator(folder))
      if (entry.path().extension() == ".c3d") {
        std::ifstream in(entry.path(), std::ios::binary);
        corpus.push_back(shortened(std::string((std::istreambuf_iterator<char>(in)), {})));
      }
  ASSERT_GT(corpus.size(), 10u);
  std::mt19937 rng(seed);
  Outcome outcome;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  long variants = 0;
  while (std::chrono::steady_clock::now() < end) {
    const std::string& original = corpus[rng() % corpus.size()];
    const std::string variant = mutate(original, corpus[rng() % corpus.size()], rng);
    read_variant(variant, outcome);
    if (HasFatalFailure()) return;
    ++variants;
  }
  RecordProperty("variants", static_cast<int>(variants));
  EXPECT_GT(outcome.results, 0);
  EXPECT_GT(outcome.errors, 0);
}

TEST(C3dMutationCases, HugeDeclaredCountsAreBoundedByTheFileSize) {
  // 65535 points per frame and 65535 frames declared in a file of two blocks plus one frame.
  std::string bytes(3 * 512, '\0');
  bytes[0] = 2;
  bytes[1] = 0x50;
  bytes[2] = bytes[3] = '\xFF';  // points
  bytes[4] = bytes[5] = '\xFF';  // analog values per frame
  bytes[6] = 1;                  // first frame
  bytes[8] = bytes[9] = '\xFF';  // last frame
  const float scale = -1.0f;
  std::memcpy(&bytes[12], &scale, 4);
  bytes[16] = 3;  // data start block
  bytes[512 + 3] = 84;
  C3dReader reader(std::make_unique<std::istringstream>(bytes), "huge.c3d");
  EXPECT_EQ(reader.info().frame_count, 0);
  EXPECT_FALSE(reader.info().warnings.empty());
  Frame frame;
  EXPECT_FALSE(reader.read_frame(frame));
}

}  // namespace
