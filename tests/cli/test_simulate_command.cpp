// The `s2kf simulate` command: files written, reproducibility, consistency, bad options.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/sim/subject.hpp>

#include "cli_runner.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "test_files.hpp"

#ifdef S2KF_CLI

namespace {

namespace fs = std::filesystem;

using s2kf::test_support::CommandResult;

CommandResult run_cli(const std::string& arguments) { return s2kf::test_support::run_command(arguments); }

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string out_path(const std::string& name) { return (s2kf::test_support::scratch("") / name).string(); }

std::vector<std::vector<std::string>> read_csv(const std::string& path) {
  return s2kf::test_support::csv_rows(s2kf::test_support::read_text(path));
}

TEST(SimulateCommand, ListNamesTheBundledMotions) {
  const CommandResult run = run_cli("simulate --list");
  ASSERT_EQ(run.status, 0) << run.output;
  for (const char* name : {"handstand", "walk", "squats", "jumping_jacks", "arm_circles", "cartwheel",
                           "forward_roll", "random_sweep", "static", "dance"})
    EXPECT_NE(run.output.find(name), std::string::npos) << name << " missing from:\n" << run.output;
}

TEST(SimulateCommand, WritesAReadableC3dWithTruthAndCleanMarkersThatAgree) {
  const std::string c3d = out_path("walk_test.c3d");
  const CommandResult run =
      run_cli("simulate --motion walk --seed 4 --frames 120 --blackout 0.5,0.2 --out \"" + c3d + "\"");
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("120 frames"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("50 markers"), std::string::npos) << run.output;

  const s2kf::c3d::Recording recording = s2kf::c3d::read_c3d(c3d);
  const s2kf::body::BodyModel model = s2kf::body::mmm_body_model();
  ASSERT_EQ(recording.frame_count(), 120);
  ASSERT_EQ(recording.point_count(), 50);
  EXPECT_DOUBLE_EQ(recording.info.rate, 100.0);
  for (int m = 0; m < 50; ++m) EXPECT_EQ(recording.info.labels[m].name, model.markers[m].name);
  // The blackout hides frames 50..69 entirely; the rest is visible (no random occlusion asked).
  for (Eigen::Index k = 0; k < 120; ++k) EXPECT_EQ(recording.visible.col(k).any(), k < 50 || k >= 70) << k;

  const auto truth = read_csv(out_path("walk_test_truth.csv"));
  const auto clean = read_csv(out_path("walk_test_clean.csv"));
  ASSERT_EQ(truth.size(), 121u);
  ASSERT_EQ(clean.size(), 121u);
  std::vector<std::string> expected_columns{"frame",  "time",      "root_x",     "root_y",
                                            "root_z", "root_roll", "root_pitch", "root_yaw"};
  for (const auto& joint : model.joints) expected_columns.push_back(joint.name);
  EXPECT_EQ(truth[0], expected_columns);
  ASSERT_EQ(clean[0].size(), 2u + 150u);
  EXPECT_EQ(clean[0][2], "C7_x");
  EXPECT_EQ(clean[0][151], "RTOE_z");

  // The truth (as written, %.9g) through the subject of the same seed gives the clean markers,
  // and the C3D holds the clean markers plus about 0.7 mm of noise (stored as 32-bit floats).
  const s2kf::sim::Subject subject = s2kf::sim::make_subject(model, s2kf::sim::SubjectOptions{}, 4);
  for (std::size_t row = 1; row < truth.size(); row += 10) {
    s2kf::body::Pose pose;
    for (int c = 0; c < 3; ++c) pose.root_position(c) = std::stod(truth[row][2 + c]);
    for (int c = 0; c < 3; ++c) pose.root_rpy(c) = std::stod(truth[row][5 + c]);
    for (int j = 0; j < 40; ++j) pose.joints(j) = std::stod(truth[row][8 + j]);
    const double time = std::stod(truth[row][1]);
    const Eigen::Matrix3Xd expected = s2kf::sim::subject_marker_positions(subject, pose, time);
    for (int m = 0; m < 50; ++m)
      for (int c = 0; c < 3; ++c) {
        const double clean_value = std::stod(clean[row][2 + 3 * m + c]);
        ASSERT_NEAR(clean_value, expected(c, m), 1e-3) << "frame " << row - 1 << " marker " << m;
        const Eigen::Index k = static_cast<Eigen::Index>(row) - 1;
        if (recording.visible(m, k)) {
          ASSERT_NEAR(recording.frame(k)(c, m), clean_value, 5.0);
        }
      }
  }
}

TEST(SimulateCommand, TheSameSeedGivesTheSameBytesAndAnotherSeedOthers) {
  const auto make = [](const std::string& name, int seed) {
    return run_cli("simulate --motion squats --frames 60 --occlusion 0.01,20 --seed " + std::to_string(seed) +
                   " --out \"" + out_path(name) + ".c3d\"");
  };
  ASSERT_EQ(make("same_a", 7).status, 0);
  ASSERT_EQ(make("same_b", 7).status, 0);
  ASSERT_EQ(make("other", 8).status, 0);
  for (const char* suffix : {".c3d", "_truth.csv", "_clean.csv"}) {
    const std::string a = read_bytes(out_path(std::string("same_a") + suffix));
    ASSERT_FALSE(a.empty()) << suffix;
    EXPECT_EQ(a, read_bytes(out_path(std::string("same_b") + suffix))) << suffix;
  }
  EXPECT_NE(read_bytes(out_path("same_a.c3d")), read_bytes(out_path("other.c3d")));
  EXPECT_NE(read_bytes(out_path("same_a_clean.csv")), read_bytes(out_path("other_clean.csv")));
}

TEST(SimulateCommand, BadOptionsExitWithStatusOneAndASentence) {
  const std::string out = " --out \"" + out_path("bad.c3d") + "\"";
  const struct {
    std::string arguments, expected;
  } cases[] = {
      {"simulate --motion moonwalk" + out, "unknown motion 'moonwalk'"},
      {"simulate --motion walk --occlusion 1.5,100" + out, "probability p must lie in [0, 1]"},
      {"simulate --motion walk --occlusion 0.1" + out, "--occlusion expects p,lambda"},
      {"simulate --motion walk --noise -1" + out, "--noise must lie in [0, 1000] mm"},
      {"simulate --motion walk", "needs --out"},
      {"simulate --motion walk --dropout elbow,1,1" + out, "unknown segment 'elbow'"},
  };
  for (const auto& c : cases) {
    const CommandResult run = run_cli(c.arguments);
    EXPECT_EQ(run.status, 1) << c.arguments << "\n" << run.output;
    EXPECT_NE(run.output.find("s2kf: "), std::string::npos) << run.output;
    EXPECT_NE(run.output.find(c.expected), std::string::npos) << c.arguments << "\n" << run.output;
  }
  EXPECT_FALSE(fs::exists(out_path("bad.c3d")));
}

}  // namespace

#endif  // S2KF_CLI
