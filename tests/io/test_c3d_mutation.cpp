// Thousands of corrupted variants of the real C3D files (seeded, so every run tests the same
// ones): the reader must either throw C3dError or return a consistent result, never crash, hang,
// allocate without bound or throw anything else. Runs under ASan/UBSan in CI.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

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
