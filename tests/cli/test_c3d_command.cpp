// `s2kf c3d`: what it reports of a real file, and the sentence it gives for a bad one.
#include <s2kf/io/c3d_reader.hpp>

#include "cli_runner.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>

namespace {

using s2kf::c3d::read_c3d;
using s2kf::c3d::Recording;

std::string data_path(const std::string& file) { return std::string(S2KF_C3D_DATA_DIR) + "/" + file; }

// The program's output and exit status (cli_runner.hpp).
std::string run_cli(const std::string& arguments, int& status) {
  const s2kf::test_support::CommandResult result = s2kf::test_support::run_command(arguments);
  status = result.status;
  return result.output;
}

TEST(C3dCommand, JsonReportsCountsLabelsMissingAndFrames) {
  int status = 0;
  const std::string out = run_cli("c3d --json --frames 0:2 " + data_path("BTS.c3d"), status);
  ASSERT_EQ(status, 0) << out;
  const auto json = nlohmann::json::parse(out);
  EXPECT_EQ(json["processor"], "intel");
  EXPECT_EQ(json["format"], "float");
  EXPECT_EQ(json["points"], 22);
  EXPECT_EQ(json["frames"], 2);
  EXPECT_EQ(json["labels"][1], "r should");
  EXPECT_EQ(json["data"].size(), 2u);
  EXPECT_TRUE(json["data"][0][0].is_null());  // BTS frame 0 point 0 is missing
  std::int64_t missing = 0;
  for (const auto& item : json["missing"].items()) missing += item.value().get<std::int64_t>();
  const Recording r = read_c3d(data_path("BTS.c3d"));
  EXPECT_EQ(missing, (!r.visible.leftCols(2)).count());
}

TEST(C3dCommand, UnreadableFileAndBadRangeFailWithASentence) {
  int status = 0;
  std::string out = run_cli("c3d " + data_path("Empty.c3d"), status);
  EXPECT_NE(status, 0);
  EXPECT_NE(out.find("s2kf: Empty.c3d: not a C3D file: the file is empty"), std::string::npos) << out;
  out = run_cli("c3d --frames 9:3 " + data_path("BTS.c3d"), status);
  EXPECT_NE(status, 0);
  EXPECT_NE(out.find("--frames 9:3"), std::string::npos) << out;
}

}  // namespace
