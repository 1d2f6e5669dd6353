// The output options of `s2kf track` (issue 18) through the program itself: --formats writes exactly
// the chosen files plus the summary and marker report, --derivatives adds _vel.csv and _acc.csv with
// the CSV's header and rows, --bvh-units cm scales the BVH, and name clashes and unknown formats are
// refused before anything is written. Runs data/handstand.c3d uncalibrated at 93 samples (about 0.5 s).
#include "../cli_runner.hpp"
#include "motion_test_support.hpp"
#include "test_files.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>
#include "address_sanitizer.hpp"

namespace s2kf {
namespace {

namespace fs = std::filesystem;
using test_support::read_text_file;
using test_support::run_command;
using test_support::scratch_directory;

const std::string kFastTrack =
    "track " + std::string(S2KF_DATA_DIR) + "/handstand.c3d --no-calibrate --samples 93 --quiet";
using test_support::kHandstandFrames;
using test_support::lines_of;

std::set<std::string> file_names_in(const std::string& dir) {
  std::set<std::string> names;
  if (!fs::exists(dir)) return names;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    names.insert(entry.path().filename().string());
  return names;
}

/// The numbers of every OFFSET line of a BVH, in file order.
std::vector<double> bvh_offsets(const std::string& path) {
  std::vector<double> offsets;
  for (const std::string& line : lines_of(read_text_file(path))) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword != "OFFSET") continue;
    for (double value; words >> value;) offsets.push_back(value);
  }
  return offsets;
}

TEST(OutputOptions, FormatsWritesExactlyTheChosenFilesAndTheAlwaysWrittenOnes) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const std::string dir = scratch_directory("output_options_formats");
  const auto result = run_command(kFastTrack + " --formats csv,osim --out " + dir + "/run");
  ASSERT_EQ(result.status, 0) << result.output;
  EXPECT_EQ(file_names_in(dir), (std::set<std::string>{"run.csv", "run.osim", "run.json", "run_markers.csv",
                                                       "run_segments.csv"}));
  EXPECT_EQ(lines_of(read_text_file(dir + "/run.csv")).size(), kHandstandFrames + 1u);
}

TEST(OutputOptions, DerivativesWriteVelocityAndAccelerationWithTheCsvHeaderAndOneRowPerFrame) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const std::string dir = scratch_directory("output_options_derivatives");
  const auto result = run_command(kFastTrack + " --formats csv --derivatives --out " + dir + "/run");
  ASSERT_EQ(result.status, 0) << result.output;
  EXPECT_EQ(file_names_in(dir), (std::set<std::string>{"run.csv", "run_vel.csv", "run_acc.csv", "run.json",
                                                       "run_markers.csv", "run_segments.csv"}));
  const std::vector<std::string> motion = lines_of(read_text_file(dir + "/run.csv"));
  ASSERT_EQ(motion.size(), kHandstandFrames + 1u);
  ASSERT_EQ(motion[0].rfind("frame,time,root_x,root_y,root_z,root_roll,root_pitch,root_yaw,BPx,", 0), 0u);
  for (const std::string suffix : {"_vel.csv", "_acc.csv"}) {
    const std::vector<std::string> derivative = lines_of(read_text_file(dir + "/run" + suffix));
    ASSERT_EQ(derivative.size(), motion.size()) << suffix;
    EXPECT_EQ(derivative[0], motion[0]) << suffix;
    for (std::size_t row = 1; row < motion.size(); ++row) {  // same frame and time in the first two columns
      const auto frame_and_time = [](const std::string& line) {
        return line.substr(0, line.find(',', line.find(',') + 1));
      };
      ASSERT_EQ(frame_and_time(derivative[row]), frame_and_time(motion[row])) << suffix << " row " << row;
    }
  }
}

TEST(OutputOptions, CentimetreBvhOffsetsAreAHundredTimesTheMetreOnes) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const std::string dir = scratch_directory("output_options_bvh_units");
  const auto metres = run_command(kFastTrack + " --formats bvh --out " + dir + "/metres");
  ASSERT_EQ(metres.status, 0) << metres.output;
  const auto centimetres =
      run_command(kFastTrack + " --formats bvh --bvh-units cm --out " + dir + "/centimetres");
  ASSERT_EQ(centimetres.status, 0) << centimetres.output;
  const std::vector<double> in_metres = bvh_offsets(dir + "/metres.bvh");
  const std::vector<double> in_centimetres = bvh_offsets(dir + "/centimetres.bvh");
  ASSERT_EQ(in_metres.size(), in_centimetres.size());
  ASSERT_GE(in_metres.size(), 3u * 17);  // the root and the 16 joint groups at least
  double longest_m = 0;
  for (std::size_t i = 0; i < in_metres.size(); ++i) {
    EXPECT_NEAR(in_centimetres[i], 100 * in_metres[i], 1e-4) << "offset number " << i;  // 6 decimals each
    longest_m = std::max(longest_m, std::abs(in_metres[i]));
  }
  EXPECT_GT(longest_m, 0.2);  // a thigh or a trunk segment: the files are in metres, not millimetres
  EXPECT_LT(longest_m, 1.0);
}

TEST(OutputOptions, TwoRecordingsWithTheSameNameIntoOneFolderAreRefusedBeforeWritingAnything) {
  const std::string dir = scratch_directory("output_options_same_name");
  for (const std::string take : {"a", "b"}) {
    fs::create_directories(dir + "/" + take);
    fs::copy_file(std::string(S2KF_DATA_DIR) + "/handstand.c3d", dir + "/" + take + "/handstand.c3d");
  }
  const auto result =
      run_command("track " + dir + "/a/handstand.c3d " + dir +
                  "/b/handstand.c3d --no-calibrate --samples 93 --quiet --out " + dir + "/out");
  EXPECT_EQ(result.status, 1) << result.output;
  const std::vector<std::string> message = lines_of(result.output);
  ASSERT_EQ(message.size(), 1u) << result.output;
  EXPECT_NE(message[0].find("two recordings would both write"), std::string::npos) << result.output;
  EXPECT_EQ(file_names_in(dir + "/out"), std::set<std::string>{});
}

TEST(OutputOptions, AnOutputFileNameThatIsADirectoryIsRefusedBeforeWritingAnything) {
  const std::string dir = scratch_directory("output_options_directory_name");
  fs::create_directories(dir + "/run.bvh");
  const auto result = run_command(kFastTrack + " --out " + dir + "/run");
  EXPECT_EQ(result.status, 1) << result.output;
  const std::vector<std::string> message = lines_of(result.output);
  ASSERT_EQ(message.size(), 1u) << result.output;
  EXPECT_NE(message[0].find("run.bvh: it is a directory"), std::string::npos) << result.output;
  EXPECT_EQ(file_names_in(dir), std::set<std::string>{"run.bvh"});  // no output and no .tmp file
  EXPECT_TRUE(fs::is_empty(dir + "/run.bvh"));
}

TEST(OutputOptions, AnUnknownFormatIsRefused) {
  const std::string dir = scratch_directory("output_options_bogus");
  const auto result = run_command(kFastTrack + " --formats csv,bogus --out " + dir + "/run");
  EXPECT_NE(result.status, 0) << result.output;
  EXPECT_NE(result.output.find("bogus"), std::string::npos) << result.output;
  EXPECT_EQ(file_names_in(dir), std::set<std::string>{});
}

}  // namespace
}  // namespace s2kf
