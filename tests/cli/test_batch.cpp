// Batches of `s2kf track` through the program (issues 16 and 17): outputs mirror the input's
// subfolders at any --jobs, one bad file among good ones fails alone (named, recorded, nothing
// partial left), --shard deals every recording to exactly one shard, `s2kf summarize` gives one CSV
// row per summary with the summary's values, and the seconds per stage add up. Recordings run
// uncalibrated at 93 samples (about half a second each) unless a test needs the calibration.
#include "../cli_runner.hpp"
#include "motion_test_support.hpp"
#include "test_files.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>
#include "address_sanitizer.hpp"

namespace s2kf {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test_support::read_text_file;
using test_support::run_command;
using test_support::scratch_directory;

const std::string kFast = " --no-calibrate --samples 93 --quiet";
using test_support::kHandstandFrames;
using test_support::kWalkFrames;
using test_support::lines_of;

std::string data(const std::string& name) { return std::string(S2KF_DATA_DIR) + "/" + name; }

void copy_into(const std::string& from, const std::string& to) {
  fs::create_directories(fs::path(to).parent_path());
  fs::copy_file(from, to, fs::copy_options::overwrite_existing);
}

/// Every file below `dir`, as paths relative to it.
std::set<std::string> files_below(const std::string& dir) {
  std::set<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file()) files.insert(entry.path().lexically_relative(dir).generic_string());
  return files;
}

json read_json(const std::string& path) { return json::parse(read_text_file(path)); }

/// A CSV text as rows of fields (RFC 4180 quoting: "" inside quotes is one quote).
std::vector<std::vector<std::string>> parse_csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows(1, std::vector<std::string>(1));
  bool quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        rows.back().back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        rows.back().back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      rows.back().emplace_back();
    } else if (c == '\n') {
      rows.emplace_back(1);
    } else {
      rows.back().back() += c;
    }
  }
  if (rows.back() == std::vector<std::string>(1)) rows.pop_back();  // the final line break
  return rows;
}

/// Two subjects with a take of the same name (S01/Walk01.c3d: the walk, S02/Walk01.c3d: the
/// handstand, so a mix-up shows in the frame counts).
std::string two_subjects(const std::string& name) {
  const std::string dir = scratch_directory(name);
  copy_into(data("walk.c3d"), dir + "/in/S01/Walk01.c3d");
  copy_into(data("handstand.c3d"), dir + "/in/S02/Walk01.c3d");
  return dir;
}

TEST(Batch, OutputsMirrorTheSubfoldersAtOneJobAndAtTwo) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const std::string dir = two_subjects("batch_mirror");
  std::map<int, std::string> csv_of_jobs;
  for (int jobs : {1, 2}) {
    const std::string out = dir + "/out" + std::to_string(jobs);
    const auto result = run_command("track " + dir + "/in --formats csv --jobs " + std::to_string(jobs) +
                                    kFast + " --out " + out + "/");
    ASSERT_EQ(result.status, 0) << result.output;
    EXPECT_EQ(files_below(out),
              (std::set<std::string>{"S01/Walk01.csv", "S01/Walk01.json", "S01/Walk01_markers.csv",
                                     "S01/Walk01_segments.csv", "S02/Walk01.csv", "S02/Walk01.json",
                                     "S02/Walk01_markers.csv", "S02/Walk01_segments.csv"}));
    EXPECT_EQ(lines_of(read_text_file(out + "/S01/Walk01.csv")).size(), kWalkFrames + 1);
    EXPECT_EQ(lines_of(read_text_file(out + "/S02/Walk01.csv")).size(), kHandstandFrames + 1);
    EXPECT_EQ(read_json(out + "/S01/Walk01.json")["input"], dir + "/in/S01/Walk01.c3d");
    EXPECT_EQ(read_json(out + "/S02/Walk01.json")["input"], dir + "/in/S02/Walk01.c3d");
    csv_of_jobs[jobs] = read_text_file(out + "/S01/Walk01.csv") + read_text_file(out + "/S02/Walk01.csv");
  }
  EXPECT_TRUE(csv_of_jobs[1] == csv_of_jobs[2]) << "two jobs wrote other motions than one";
}

TEST(Batch, OneBadFileFailsAloneNamedAndRecordedAndLeavesNoPartialOutput) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const std::string dir = two_subjects("batch_bad_file");
  {
    std::ofstream broken(dir + "/in/S02/broken.c3d", std::ios::binary);
    broken << std::string(2000, 'x');  // not a C3D file
  }
  const std::string out = dir + "/out";
  const auto result = run_command("track " + dir + "/in --formats csv --jobs 2" + kFast + " --out " + out);
  EXPECT_EQ(result.status, 1) << result.output;
  const std::string bad = dir + "/in/S02/broken.c3d";
  const std::vector<std::string> lines = lines_of(result.output);
  ASSERT_EQ(lines.size(), 2u) << result.output;  // --quiet: the failure and the closing sentence
  EXPECT_EQ(lines[0].rfind("s2kf: " + bad + ": not a C3D file", 0), 0u) << result.output;
  EXPECT_EQ(lines[1].rfind("s2kf: 1 of 3 recordings could not be tracked: " + bad, 0), 0u) << result.output;
  EXPECT_EQ(files_below(out),
            (std::set<std::string>{"S01/Walk01.csv", "S01/Walk01.json", "S01/Walk01_markers.csv",
                                   "S01/Walk01_segments.csv", "S02/Walk01.csv", "S02/Walk01.json",
                                   "S02/Walk01_markers.csv", "S02/Walk01_segments.csv", "S02/broken.json"}));
  const json record = read_json(out + "/S02/broken.json");
  EXPECT_EQ(record["input"], bad);
  EXPECT_EQ(record["status"], "failed");
  EXPECT_EQ(record["error"].get<std::string>(), lines[0].substr(6));
}

TEST(Batch, SummarizeGivesOneRowPerRecordingWithTheValuesOfItsSummary) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const std::string dir = two_subjects("batch_summarize");
  {
    std::ofstream broken(dir + "/in/S02/broken.c3d", std::ios::binary);
    broken << "not a C3D file, \"quoted\"\n";
  }
  const std::string out = dir + "/out";
  // Calibrated on 60 frames so the calibration columns have values.
  const auto tracked = run_command("track " + dir +
                                   "/in --formats csv --calibration-frames 60 --samples 93 "
                                   "--quiet --out " +
                                   out);
  ASSERT_EQ(tracked.status, 1) << tracked.output;
  std::ofstream(out + "/subject.json") << "{\"not\": \"a summary\"}";  // JSON, but no summary: left out
  const auto result = run_command("summarize " + out);
  ASSERT_EQ(result.status, 0) << result.output;
  const auto rows = parse_csv(result.output);
  const std::vector<std::string> header{"result",
                                        "input",
                                        "status",
                                        "error",
                                        "frames",
                                        "frames_tracked",
                                        "rate_hz",
                                        "method",
                                        "marker_set",
                                        "markers_used",
                                        "labels_ignored",
                                        "height_mm",
                                        "mean_marker_distance_mm",
                                        "converged_frame",
                                        "mean_marker_distance_all_frames_mm",
                                        "calibration_frames",
                                        "calibration_before_mm",
                                        "calibration_after_mm",
                                        "smoothed",
                                        "warnings",
                                        "warning_messages",
                                        "seconds_read",
                                        "seconds_marker_set",
                                        "seconds_height",
                                        "seconds_calibration",
                                        "seconds_tracking",
                                        "seconds_smoothing",
                                        "seconds_writing",
                                        "seconds_total"};
  ASSERT_EQ(rows.size(), 4u) << result.output;
  ASSERT_EQ(rows[0], header);
  std::map<std::string, std::string> row;  // column -> value, for the row being checked
  const auto take = [&](std::size_t r) {
    ASSERT_EQ(rows[r].size(), header.size()) << "row " << r;
    for (std::size_t c = 0; c < header.size(); ++c) row[header[c]] = rows[r][c];
  };
  // Rows sorted by result: S01/Walk01, S02/Walk01, S02/broken.
  const std::vector<std::string> results{"S01/Walk01", "S02/Walk01", "S02/broken"};
  for (std::size_t r = 1; r <= 2; ++r) {
    take(r);
    const json summary = read_json(out + "/" + results[r - 1] + ".json");
    EXPECT_EQ(row["result"], results[r - 1]);
    EXPECT_EQ(row["input"], summary["input"].get<std::string>());
    EXPECT_EQ(row["status"], "tracked");
    EXPECT_EQ(row["error"], "");
    EXPECT_EQ(std::stol(row["frames"]), summary["frames"].get<long>());
    EXPECT_EQ(std::stol(row["frames_tracked"]), summary["frames_tracked"].get<long>());
    EXPECT_EQ(std::stod(row["rate_hz"]), summary["rate"].get<double>());
    EXPECT_EQ(row["method"], "s2kf");
    EXPECT_EQ(row["marker_set"], summary["marker_set"].get<std::string>());
    EXPECT_EQ(std::stoul(row["markers_used"]), summary["markers_used"].size());
    EXPECT_EQ(std::stoul(row["labels_ignored"]), summary["labels_ignored"].size());
    EXPECT_EQ(std::stod(row["height_mm"]), summary["height_mm"].get<double>());
    EXPECT_EQ(std::stod(row["mean_marker_distance_mm"]), summary["mean_marker_distance_mm"].get<double>());
    EXPECT_EQ(std::stol(row["converged_frame"]), summary["converged_frame"].get<long>());
    EXPECT_EQ(std::stod(row["mean_marker_distance_all_frames_mm"]),
              summary["mean_marker_distance_all_frames_mm"].get<double>());
    EXPECT_EQ(std::stol(row["calibration_frames"]), 60);
    EXPECT_EQ(std::stod(row["calibration_before_mm"]),
              summary["calibration"]["mean_marker_distance_before_mm"].get<double>());
    EXPECT_EQ(std::stod(row["calibration_after_mm"]),
              summary["calibration"]["mean_marker_distance_after_mm"].get<double>());
    EXPECT_EQ(row["smoothed"], "false");
    EXPECT_EQ(std::stoul(row["warnings"]), summary["warnings"].size());
    double total = 0;
    for (const std::string stage :
         {"read", "marker_set", "height", "calibration", "tracking", "smoothing", "writing"}) {
      EXPECT_EQ(std::stod(row["seconds_" + stage]), summary["seconds_per_stage"][stage].get<double>())
          << stage;
      total += summary["seconds_per_stage"][stage].get<double>();
    }
    EXPECT_NEAR(std::stod(row["seconds_total"]), total, 1e-12 * total);
    EXPECT_GT(std::stod(row["seconds_calibration"]), 0);
  }
  EXPECT_EQ(std::stol(rows[1][4]), static_cast<long>(kWalkFrames));  // S01 is the walk
  EXPECT_EQ(std::stol(rows[2][4]), static_cast<long>(kHandstandFrames));
  take(3);
  EXPECT_EQ(row["result"], "S02/broken");
  EXPECT_EQ(row["status"], "failed");
  EXPECT_EQ(row["error"], read_json(out + "/S02/broken.json")["error"].get<std::string>());
  EXPECT_NE(row["error"].find("S02/broken.c3d: "), std::string::npos) << row["error"];
  EXPECT_EQ(row["frames"], "");
  EXPECT_EQ(row["seconds_total"], "");
  // --out writes the same table to a file.
  const auto to_file = run_command("summarize " + out + " --out " + dir + "/table.csv");
  ASSERT_EQ(to_file.status, 0) << to_file.output;
  EXPECT_EQ(read_text_file(dir + "/table.csv"), result.output);
  EXPECT_NE(to_file.output.find("3 recordings, 1 of them failed"), std::string::npos) << to_file.output;
}

TEST(Batch, SummarizeRefusesWhatIsNoResultsFolder) {
  const std::string dir = scratch_directory("batch_summarize_refuses");
  auto result = run_command("summarize " + dir);
  EXPECT_EQ(result.status, 1) << result.output;
  EXPECT_NE(result.output.find("holds no tracking summaries"), std::string::npos) << result.output;
  result = run_command("summarize " + dir + "/missing");
  EXPECT_EQ(result.status, 1) << result.output;
  EXPECT_NE(result.output.find("no such folder"), std::string::npos) << result.output;
}

/// The recordings shard I/N would track (the input paths of --dry-run's "INPUT -> PREFIX" lines).
std::vector<std::string> shard_listing(const std::string& folder, std::size_t index, std::size_t count,
                                       const std::string& out) {
  const auto result = run_command("track " + folder + " --dry-run --out " + out + " --shard " +
                                  std::to_string(index) + "/" + std::to_string(count));
  EXPECT_EQ(result.status, 0) << result.output;
  std::vector<std::string> inputs;
  for (const std::string& line : lines_of(result.output)) {
    const auto arrow = line.find(" -> ");
    if (arrow == std::string::npos) continue;  // "shard I/N holds none of the ..."
    inputs.push_back(line.substr(0, arrow));
    // The prefix mirrors the input's path below the folder.
    const std::string relative = fs::path(line.substr(0, arrow)).lexically_relative(folder).generic_string();
    EXPECT_EQ(line.substr(arrow + 4), out + "/" + relative.substr(0, relative.size() - 4)) << line;
  }
  return inputs;
}

TEST(Batch, EveryRecordingIsInExactlyOneShardInTheOrderOfItsPath) {
  const std::string dir = scratch_directory("batch_shards");
  const std::string folder = dir + "/in";
  // 23 recordings in nested folders (their content is not read by --dry-run), created out of
  // order, and two files that are not recordings.
  std::vector<std::string> relative;
  for (int k = 22; k >= 0; --k) {
    const std::string path = "S" + std::to_string(k % 4) + (k % 3 ? "/day" + std::to_string(k % 2) : "") +
                             "/trial" + std::to_string(k) + ".c3d";
    relative.push_back(path);
    fs::create_directories(fs::path(folder + "/" + path).parent_path());
    std::ofstream(folder + "/" + path) << "x";
  }
  std::ofstream(folder + "/S0/notes.txt") << "x";
  std::ofstream(folder + "/S1/trial.c3d.bak") << "x";
  std::vector<std::string> names;  // the sort key: the path without ".c3d"
  for (const std::string& path : relative) names.push_back(path.substr(0, path.size() - 4));
  std::sort(names.begin(), names.end());
  for (std::size_t count : {1, 2, 3, 5, 7, 23, 30}) {
    std::map<std::string, int> times_seen;
    for (std::size_t index = 0; index < count; ++index) {
      const std::vector<std::string> inputs = shard_listing(folder, index, count, dir + "/out");
      // Shard I holds the recordings at places I, I + N, I + 2N, ... of the sorted names.
      std::vector<std::string> expected;
      for (std::size_t k = index; k < names.size(); k += count)
        expected.push_back(folder + "/" + names[k] + ".c3d");
      EXPECT_EQ(inputs, expected) << "shard " << index << "/" << count;
      for (const std::string& input : inputs) ++times_seen[input];
    }
    ASSERT_EQ(times_seen.size(), relative.size()) << "N = " << count;
    for (const auto& [input, times] : times_seen) EXPECT_EQ(times, 1) << input << ", N = " << count;
  }
  EXPECT_EQ(shard_listing(folder, 4, 7, dir + "/out"), shard_listing(folder, 4, 7, dir + "/out"));
  EXPECT_FALSE(fs::exists(dir + "/out"));  // a dry run writes nothing
}

TEST(Batch, AMalformedShardIsRefused) {
  for (const std::string shard : {"3/3", "0/0", "1", "a/b", "1/4/2"}) {
    const auto result = run_command("track " + data("walk.c3d") + " --dry-run --shard " + shard);
    EXPECT_EQ(result.status, 1) << shard << ": " << result.output;
    EXPECT_EQ(lines_of(result.output).size(), 1u) << result.output;
    EXPECT_NE(result.output.find("--shard " + shard + ": "), std::string::npos) << result.output;
  }
}

TEST(Batch, OutEndingInASlashOrNamingAFolderIsAFolderForOneRecordingToo) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const std::string dir = scratch_directory("batch_out_folder");
  auto result =
      run_command("track " + data("walk.c3d") + " --formats csv" + kFast + " --out " + dir + "/new/");
  ASSERT_EQ(result.status, 0) << result.output;
  EXPECT_EQ(files_below(dir + "/new"),
            (std::set<std::string>{"walk.csv", "walk.json", "walk_markers.csv", "walk_segments.csv"}));
  fs::create_directories(dir + "/existing");
  result =
      run_command("track " + data("walk.c3d") + " --formats csv" + kFast + " --out " + dir + "/existing");
  ASSERT_EQ(result.status, 0) << result.output;
  EXPECT_EQ(files_below(dir + "/existing"),
            (std::set<std::string>{"walk.csv", "walk.json", "walk_markers.csv", "walk_segments.csv"}));
}

TEST(Batch, AFileWhereAnOutputFolderMustGoIsRefusedBeforeAnythingRuns) {
  const std::string dir = two_subjects("batch_file_in_the_way");
  std::ofstream(dir + "/out") << "a file";
  const auto result = run_command("track " + dir + "/in" + kFast + " --out " + dir + "/out");
  EXPECT_EQ(result.status, 1) << result.output;
  EXPECT_EQ(lines_of(result.output).size(), 1u) << result.output;
  EXPECT_NE(result.output.find("out: it is not a directory"), std::string::npos) << result.output;
}

TEST(Batch, TheC3dCommandOnAFolderSaysItIsAFolder) {
  const std::string dir = scratch_directory("batch_c3d_folder");
  const auto result = run_command("c3d " + dir);
  EXPECT_EQ(result.status, 1) << result.output;
  EXPECT_EQ(lines_of(result.output).size(), 1u) << result.output;
  EXPECT_NE(result.output.find("a folder, not a C3D file"), std::string::npos) << result.output;
}

TEST(Batch, SecondsPerStageAreInTheSummaryAndPrintedWithVerbose) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const std::string dir = scratch_directory("batch_stage_times");
  const auto start = std::chrono::steady_clock::now();
  const auto result =
      run_command("track " + data("handstand.c3d") +
                  " --formats csv --calibration-frames 60 --samples 93 --verbose --out " + dir + "/run");
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(result.status, 0) << result.output;
  const json summary = read_json(dir + "/run.json");
  const json& times = summary["seconds_per_stage"];
  double sum = 0;
  std::ostringstream printed;
  printed << "Seconds per stage:";
  for (const std::string stage :
       {"read", "marker_set", "height", "calibration", "tracking", "smoothing", "writing"}) {
    ASSERT_TRUE(times.contains(stage)) << stage;
    const double seconds = times[stage].get<double>();
    EXPECT_GE(seconds, 0) << stage;
    sum += seconds;
    char text[64];
    std::snprintf(text, sizeof text, " %s %.3f%s", stage.c_str(), seconds, stage == "writing" ? "" : ",");
    printed << text;
  }
  EXPECT_EQ(times.size(), 7u);
  EXPECT_NE(result.output.find(printed.str()), std::string::npos) << printed.str() << "\n" << result.output;
  EXPECT_EQ(times["smoothing"].get<double>(), 0);  // not smoothed
  for (const std::string stage : {"read", "marker_set", "height", "calibration", "tracking", "writing"})
    EXPECT_GT(times[stage].get<double>(), 0) << stage;  // each was done
  EXPECT_LT(sum, wall);  // stages do not overlap and all happen inside the process
  // Tracking is the sum of the per-frame times: at least half the frames take the median or more.
  const double median_seconds = summary["latency_ms"]["median"].get<double>() / 1000;
  EXPECT_GE(times["tracking"].get<double>(), 0.5 * static_cast<double>(kHandstandFrames) * median_seconds);
  EXPECT_LT(times["tracking"].get<double>(), wall);
}

}  // namespace
}  // namespace s2kf
