// `s2kf samples`: computes a sample set, loads it from the cache the second time, writes a CSV,
// and refuses bad options with a sentence.
#include "cli_runner.hpp"
#include "test_files.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

namespace {

namespace fs = std::filesystem;

// A fresh directory per test, so tests never see each other's files.
fs::path fresh_scratch(const std::string& name) {
  return s2kf::test_support::empty_scratch("samples_command/" + name);
}

// Runs the s2kf program and returns its output and exit status (cli_runner.hpp).
std::pair<std::string, int> run(const std::string& arguments) {
  const s2kf::test_support::CommandResult result = s2kf::test_support::run_command(arguments);
  return {result.output, result.status};
}

TEST(SamplesCommand, ComputesThenLoadsAndWritesCsv) {
  const fs::path dir = fresh_scratch("cli");
  const std::string cache = " --cache-dir " + (dir / "cache").string();
  auto [first, status] = run("samples --dim 3 --count 11 --json" + cache);
  ASSERT_EQ(status, 0) << first;
  EXPECT_NE(first.find("\"cached\":false"), std::string::npos) << first;
  EXPECT_NE(first.find("\"dimension\":3"), std::string::npos) << first;
  EXPECT_NE(first.find("\"count\":11"), std::string::npos) << first;
  auto [second, status2] =
      run("samples --dim 3 --count 11 --json" + cache + " --out " + (dir / "z.csv").string());
  ASSERT_EQ(status2, 0) << second;
  EXPECT_NE(second.find("\"cached\":true"), std::string::npos) << second;
  EXPECT_NE(second.find("\"seconds\":0"), std::string::npos) << second;
  std::ifstream csv(dir / "z.csv");
  std::string line;
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    EXPECT_EQ(std::count(line.begin(), line.end(), ','), 2) << line;
  }
  EXPECT_EQ(rows, 11);
}

TEST(SamplesCommand, RejectsBadOptionsWithASentence) {
  auto [few, status] = run("samples --dim 3 --count 5 --no-cache");
  EXPECT_EQ(status, 1);
  EXPECT_NE(few.find("s2kf: "), std::string::npos) << few;
  EXPECT_NE(few.find("at least 6"), std::string::npos) << few;
  auto [zero, status2] = run("samples --dim 0 --count 5 --no-cache");
  EXPECT_EQ(status2, 1) << zero;
  auto [out, status3] = run("samples --dim 2 --count 5 --no-cache --out /nonexistent-dir/z.csv");
  EXPECT_EQ(status3, 1) << out;
  EXPECT_NE(out.find("/nonexistent-dir"), std::string::npos) << out;
}

}  // namespace
