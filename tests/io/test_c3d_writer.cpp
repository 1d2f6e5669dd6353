// The C3D writer: files it writes read back bit for bit (as float32), including more than 255
// markers, more than 65535 frames and missing markers, and appear only when complete.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "s2kf/io/c3d_reader.hpp"
#include "s2kf/io/c3d_writer.hpp"
#include "test_files.hpp"

namespace {

using namespace s2kf::c3d;
using BoolArray = Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>;

std::string scratch(const std::string& name) {
  std::filesystem::create_directories(s2kf::test_support::tmp_dir());
  return std::string(s2kf::test_support::tmp_dir()) + "/" + name;
}

struct Synthetic {
  std::vector<std::string> labels;
  Eigen::MatrixXd positions;
  BoolArray visible;
};

Synthetic make_synthetic(int points, int frames, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coordinate(-3000.0, 3000.0);
  std::bernoulli_distribution gap(0.1);
  Synthetic s;
  for (int p = 0; p < points; ++p) s.labels.push_back("M" + std::to_string(p));
  s.positions.resize(3 * points, frames);
  s.visible.resize(points, frames);
  for (int f = 0; f < frames; ++f)
    for (int p = 0; p < points; ++p) {
      for (int k = 0; k < 3; ++k) s.positions(3 * p + k, f) = coordinate(rng);
      s.visible(p, f) = !gap(rng);
    }
  return s;
}

void expect_round_trip(const Synthetic& s, const Recording& r) {
  ASSERT_EQ(r.point_count(), static_cast<Eigen::Index>(s.labels.size()));
  ASSERT_EQ(r.frame_count(), s.positions.cols());
  ASSERT_TRUE((r.visible == s.visible).all());
  for (Eigen::Index f = 0; f < r.frame_count(); ++f)
    for (Eigen::Index p = 0; p < r.point_count(); ++p)
      for (int k = 0; k < 3; ++k) {
        if (s.visible(p, f)) {
          ASSERT_EQ(r.positions(3 * p + k, f),
                    static_cast<double>(static_cast<float>(s.positions(3 * p + k, f))));
        } else {
          ASSERT_TRUE(std::isnan(r.positions(3 * p + k, f)));
        }
      }
  for (std::size_t i = 0; i < s.labels.size(); ++i) ASSERT_EQ(r.info.labels[i].raw, s.labels[i]);
}

TEST(C3dWriter, RoundTripIsBitExactForFloatPositionsMasksLabelsAndRate) {
  const Synthetic s = make_synthetic(7, 40, 1);
  const std::string path = scratch("round_trip.c3d");
  write_c3d(path, s.labels, 123.25, s.positions, s.visible);
  const Recording r = read_c3d(path);
  expect_round_trip(s, r);
  EXPECT_EQ(r.info.rate, 123.25);
  EXPECT_EQ(r.info.processor, Processor::intel);
  EXPECT_EQ(r.info.format, StorageFormat::floating);
  EXPECT_EQ(r.info.units, "mm");
  EXPECT_TRUE(r.info.warnings.empty()) << r.info.warnings.front();
  // Missing markers are stored as (0,0,0) with word 4 = -1.0f, visible ones with 0.0f.
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (int p = 0; p < 7; ++p) {
    float w[4];
    std::memcpy(w, bytes.data() + r.info.data_offset + 16 * p, 16);
    if (s.visible(p, 0)) {
      EXPECT_EQ(w[3], 0.0f);
    } else {
      EXPECT_EQ(w[0], 0.0f);
      EXPECT_EQ(w[1], 0.0f);
      EXPECT_EQ(w[2], 0.0f);
      EXPECT_EQ(w[3], -1.0f);
    }
  }
  EXPECT_EQ(bytes.size() % 512, 0u);
}

TEST(C3dWriter, NanCoordinatesAreWrittenAsMissing) {
  Synthetic s = make_synthetic(3, 4, 2);
  s.visible.setConstant(true);
  s.positions(4, 2) = std::numeric_limits<double>::quiet_NaN();
  const std::string path = scratch("nan.c3d");
  write_c3d(path, s.labels, 100.0, s.positions);
  const Recording r = read_c3d(path);
  EXPECT_FALSE(r.visible(1, 2));
  EXPECT_EQ((!r.visible).count(), 1);
}

TEST(C3dWriter, MoreThan255MarkersUseLabels2) {
  const Synthetic s = make_synthetic(600, 3, 3);
  const std::string path = scratch("many_markers.c3d");
  write_c3d(path, s.labels, 60.0, s.positions, s.visible);
  C3dReader reader(path);
  ASSERT_NE(reader.parameter("POINT", "LABELS2"), nullptr);
  ASSERT_NE(reader.parameter("POINT", "LABELS3"), nullptr);
  EXPECT_EQ(reader.parameter("POINT", "LABELS")->strings.size(), 255u);
  EXPECT_EQ(reader.parameter("POINT", "LABELS3")->strings.size(), 90u);
  expect_round_trip(s, read_all(reader));
}

TEST(C3dWriter, MoreThan65535FramesAreCountedThroughLongFramesAndTrialFields) {
  const Synthetic s = make_synthetic(1, 66000, 4);
  const std::string path = scratch("many_frames.c3d");
  write_c3d(path, s.labels, 200.0, s.positions, s.visible);
  C3dReader reader(path);
  EXPECT_EQ(reader.info().frame_count, 66000);
  EXPECT_EQ(reader.parameter("POINT", "FRAMES")->words.at(0), 65535);
  EXPECT_EQ(reader.parameter("POINT", "LONG_FRAMES")->numbers.at(0), 66000.0);
  const auto& end = reader.parameter("TRIAL", "ACTUAL_END_FIELD")->words;
  EXPECT_EQ(end.at(0) | (end.at(1) << 16), 66000);
  expect_round_trip(s, read_all(reader));
  // The header last frame saturates at 65535.
  std::ifstream in(path, std::ios::binary);
  unsigned char header[10];
  in.read(reinterpret_cast<char*>(header), 10);
  EXPECT_EQ(header[8] | (header[9] << 8), 65535);
}

TEST(C3dWriter, StreamingWriterEqualsWholeRecordingWriter) {
  const Synthetic s = make_synthetic(5, 30, 5);
  const std::string whole = scratch("whole.c3d");
  const std::string streamed = scratch("streamed.c3d");
  write_c3d(whole, s.labels, 90.0, s.positions, s.visible);
  {
    C3dStreamWriter writer(streamed, s.labels, 90.0);
    for (Eigen::Index f = 0; f < s.positions.cols(); ++f) {
      const Eigen::Map<const Eigen::Matrix3Xd> frame(s.positions.col(f).data(), 3, 5);
      writer.append(frame, s.visible.col(f));
    }
    writer.finish();
    EXPECT_EQ(writer.frames_written(), 30);
  }
  std::ifstream a(whole, std::ios::binary), b(streamed, std::ios::binary);
  const std::string bytes_a((std::istreambuf_iterator<char>(a)), std::istreambuf_iterator<char>());
  const std::string bytes_b((std::istreambuf_iterator<char>(b)), std::istreambuf_iterator<char>());
  EXPECT_EQ(bytes_a, bytes_b);
}

TEST(C3dWriter, RealRecordingSurvivesARoundTrip) {
  const Recording original = read_c3d(std::string(S2KF_C3D_DATA_DIR) + "/Vicon.c3d");
  const std::string path = scratch("vicon_copy.c3d");
  write_c3d(path, original);
  const Recording copy = read_c3d(path);
  ASSERT_TRUE((copy.visible == original.visible).all());
  EXPECT_TRUE(
      (copy.positions.array() == original.positions.array() || original.positions.array().isNaN()).all());
  for (std::size_t i = 0; i < copy.info.labels.size(); ++i) {
    EXPECT_EQ(copy.info.labels[i].raw, original.info.labels[i].raw);
    EXPECT_EQ(copy.info.labels[i].subject, original.info.labels[i].subject);
  }
  EXPECT_EQ(copy.info.rate, original.info.rate);
}

TEST(C3dWriter, NothingAppearsUntilFinishAndAnAbandonedWriteLeavesNoTrace) {
  const std::string path = scratch("atomic.c3d");
  std::filesystem::remove(path);
  const Synthetic s = make_synthetic(2, 3, 6);
  {
    C3dStreamWriter writer(path, s.labels, 50.0);
    writer.append(Eigen::Matrix3Xd::Ones(3, 2));
    EXPECT_FALSE(std::filesystem::exists(path));
    EXPECT_TRUE(std::filesystem::exists(path + ".tmp"));
  }  // destroyed without finish()
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));

  // An existing file is replaced only by a complete one.
  write_c3d(path, s.labels, 50.0, s.positions, s.visible);
  const auto size_before = std::filesystem::file_size(path);
  {
    C3dStreamWriter writer(path, {"A", "B", "C"}, 50.0);
    EXPECT_THROW(writer.append(Eigen::Matrix3Xd::Ones(3, 2)), C3dError);  // wrong point count
  }
  EXPECT_EQ(std::filesystem::file_size(path), size_before);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  EXPECT_EQ(read_c3d(path).frame_count(), 3);
}

TEST(C3dWriter, BadArgumentsAreRejectedWithASentence) {
  const std::string path = scratch("bad.c3d");
  EXPECT_THROW(C3dStreamWriter(path, {"A"}, 0.0), C3dError);
  EXPECT_THROW(C3dStreamWriter(path, {std::string(300, 'x')}, 100.0), C3dError);
  EXPECT_THROW(C3dStreamWriter(path, std::vector<std::string>(65536, "m"), 100.0), C3dError);
  EXPECT_THROW(write_c3d(path, {"A", "B"}, 100.0, Eigen::MatrixXd::Zero(3, 4)), C3dError);
  EXPECT_THROW(C3dStreamWriter("/nonexistent_dir_s2kf/x.c3d", {"A"}, 100.0), C3dError);
}

}  // namespace
