// The `s2kf model` command, run as a user would run it.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/pose_columns.hpp>

#include "cli_runner.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "test_files.hpp"

namespace {

#ifdef S2KF_CLI

using s2kf::test_support::run_command;

using s2kf::test_support::csv_rows;

std::string scratch_file(const std::string& name) {
  std::filesystem::create_directories(s2kf::test_support::tmp_dir());
  return std::string(s2kf::test_support::tmp_dir()) + "/" + name;
}

TEST(CommandModel, PrintsFiftyZeroPoseMarkersScaledToTheHeight) {
  for (double height : {1750.0, 1000.0}) {
    const s2kf::test_support::CommandResult result =
        run_command(height == 1750.0 ? "model" : "model --height 1000");
    ASSERT_EQ(result.status, 0) << result.output;
    const auto rows = csv_rows(result.output);
    ASSERT_EQ(rows.size(), 51u);
    EXPECT_EQ(rows[0], (std::vector<std::string>{"marker", "x", "y", "z"}));
    for (int m = 0; m < 50; ++m) {
      const auto& row = s2kf::body::mmm::kMarkerTable[m];
      ASSERT_EQ(rows[m + 1].size(), 4u);
      EXPECT_EQ(rows[m + 1][0], row.name);
      EXPECT_NEAR(std::stod(rows[m + 1][1]), row.x * height / 1000, 1e-6);
      EXPECT_NEAR(std::stod(rows[m + 1][2]), row.y * height / 1000, 1e-6);
      EXPECT_NEAR(std::stod(rows[m + 1][3]), row.z * height / 1000, 1e-6);
    }
  }
}

TEST(CommandModel, JointsFlagPrintsTheJointTable) {
  const s2kf::test_support::CommandResult result = run_command("model --joints --height 1000");
  ASSERT_EQ(result.status, 0) << result.output;
  const auto rows = csv_rows(result.output);
  ASSERT_EQ(rows.size(), 41u);
  EXPECT_EQ(rows[0][0], "joint");
  EXPECT_EQ(rows[1][0], "BPx");
  EXPECT_EQ(rows[1][1], "root");
  EXPECT_EQ(rows[4][0], "BTx");
  EXPECT_EQ(rows[4][1], "BPy");
  EXPECT_EQ(rows[4][2], "x");
  EXPECT_NEAR(std::stod(rows[4][7]), 60, 1e-9);
  EXPECT_NEAR(std::stod(rows[30][3]), -2.26893, 1e-6);  // LKx lower
}

TEST(CommandModel, JsonAndCsvPosesGiveTheSameMarkers) {
  const std::string json = scratch_file("pose.json"), csv = scratch_file("pose.csv");
  std::ofstream(json)
      << R"({"root_position": [10, 20, 900], "root_rpy": [0.1, -0.2, 1.3], "joints": {"LKx": -1.5707963267948966, "RSx": 0.4}})";
  {
    std::ofstream out(csv);
    const auto columns = s2kf::body::pose_column_names();
    for (std::size_t k = 0; k < columns.size(); ++k) out << (k ? "," : "") << columns[k];
    out << ",extra\n0,0,10,20,900,0.1,-0.2,1.3";
    for (const auto& joint : s2kf::body::mmm::kJointTable) {
      const std::string name = joint.name;
      out << "," << (name == "LKx" ? "-1.5707963267948966" : name == "RSx" ? "0.4" : "0");
    }
    out << ",7\n1,0.01,0,0,0,0,0,0";
    for (int j = 0; j < 40; ++j) out << ",0";
    out << ",7\n";
  }
  const s2kf::test_support::CommandResult from_json = run_command("model --pose \"" + json + "\"");
  const s2kf::test_support::CommandResult from_csv = run_command("model --pose \"" + csv + "\"");
  ASSERT_EQ(from_json.status, 0) << from_json.output;
  ASSERT_EQ(from_csv.status, 0) << from_csv.output;
  EXPECT_EQ(from_json.output, from_csv.output);
  EXPECT_NE(from_json.output, run_command("model").output);
  // Root-only check on a marker of the pelvis: L3 = r + R * L3_local.
  const auto rows = csv_rows(from_json.output);
  EXPECT_EQ(rows[9][0], "L3");
}

TEST(CommandModel, BadPoseFilesAreUserErrorsNamingTheFile) {
  const std::string unknown = scratch_file("unknown_joint.json"), broken = scratch_file("broken.json"),
                    missing_column = scratch_file("missing.csv");
  std::ofstream(unknown) << R"({"joints": {"LKneeX": 0.3}})";
  std::ofstream(broken) << R"({"joints": )";
  std::ofstream(missing_column) << "frame,time,root_x\n0,0,1\n";
  for (const auto& [file, words] : std::vector<std::pair<std::string, std::string>>{
           {unknown, "unknown joint 'LKneeX'"},
           {broken, "not valid JSON"},
           {missing_column, "no column root_y"},
           {scratch_file("does_not_exist.csv"), "cannot open"}}) {
    const s2kf::test_support::CommandResult result = run_command("model --pose \"" + file + "\"");
    EXPECT_EQ(result.status, 1) << file;
    EXPECT_NE(result.output.find("s2kf: "), std::string::npos) << result.output;
    EXPECT_NE(result.output.find(file), std::string::npos) << result.output;
    EXPECT_NE(result.output.find(words), std::string::npos) << result.output;
  }
  const s2kf::test_support::CommandResult negative = run_command("model --height -3");
  EXPECT_EQ(negative.status, 1);
  EXPECT_NE(negative.output.find("--height must be a positive number"), std::string::npos) << negative.output;
}

#else
TEST(CommandModel, NeedsTheCommandLineProgram) { GTEST_SKIP() << "built without the s2kf program"; }
#endif

}  // namespace
