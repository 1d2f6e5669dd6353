// `s2kf calibrate`: writes a subject file that loads as a marker set and is taken back as
// --markerset, and names an unknown set.
#include <s2kf/app/marker_set_json.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>

#include "address_sanitizer.hpp"
#include "cli_runner.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "test_files.hpp"

namespace {

using namespace s2kf;
namespace fs = std::filesystem;

TEST(CalibrateCommand, WritesASubjectFileThatLoads) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = fs::path(s2kf::test_support::tmp_dir()) / "marker_set";
  fs::create_directories(dir);
  const std::string recording = std::string(S2KF_C3D_DATA_DIR) + "/85_02.c3d";
  const std::string subject = (dir / "subject.json").string();
  const auto [status, output] =
      test_support::run_command("calibrate " + recording + " --frames 150 --iterations 1 --out " + subject);
  ASSERT_EQ(status, 0) << output;
  EXPECT_NE(output.find("marker set cmu"), std::string::npos) << output;
  const body::MarkerSet set = app::load_marker_set(subject);
  ASSERT_TRUE(set.height_mm.has_value());
  EXPECT_EQ(set.entries.size(), 41u);
  const body::BodyModel model =
      body::apply_marker_set(body::mmm_body_model(1000), set).scaled(*set.height_mm);
  EXPECT_EQ(model.marker_count(), 41);
  // Each marker the calibration saw carries its noise, from its residual: 5 to 20 mm.
  int with_noise = 0;
  for (const body::MarkerSetEntry& entry : set.entries)
    if (entry.noise_mm) {
      ++with_noise;
      EXPECT_GE(*entry.noise_mm, 5.0) << entry.label;
      EXPECT_LE(*entry.noise_mm, 20.0) << entry.label;
    }
  EXPECT_GE(with_noise, 30);
  const std::string uniform = (dir / "uniform.json").string();
  const auto [uniform_status, uniform_output] = test_support::run_command(
      "calibrate " + recording + " --frames 150 --quiet --uniform-noise --out " + uniform);
  ASSERT_EQ(uniform_status, 0) << uniform_output;
  for (const body::MarkerSetEntry& entry : app::load_marker_set(uniform).entries)
    EXPECT_FALSE(entry.noise_mm.has_value()) << entry.label;
  // And the CLI takes it back as --markerset.
  const auto [again, again_output] =
      test_support::run_command("calibrate " + recording + " --frames 150 --iterations 1 --markerset " +
                                subject + " --out " + (dir / "again.json").string());
  EXPECT_EQ(again, 0) << again_output;
  EXPECT_NE(again_output.find("from the marker-set file"), std::string::npos) << again_output;
  const auto [bad, bad_output] =
      test_support::run_command("calibrate " + recording + " --markerset nope --out x.json");
  EXPECT_EQ(bad, 1);
  EXPECT_NE(bad_output.find("unknown marker set 'nope'"), std::string::npos) << bad_output;
}

// --shrink C sets the calibration's weak-direction shrinkage: a direction keeps mu / (mu + C) of
// the data's step, so with a huge C the offsets stay where the marker set puts them and with 0 they
// move freely; the report records the value, and a negative one is refused by name.
TEST(CalibrateCommand, ShrinkOptionPullsTheOffsetsTowardsTheMarkerSet) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = fs::path(s2kf::test_support::tmp_dir()) / "shrink";
  fs::create_directories(dir);
  const std::string recording = std::string(S2KF_C3D_DATA_DIR) + "/85_02.c3d";
  const auto calibrated = [&](const std::string& name, const std::string& options) {
    const std::string subject = (dir / (name + ".json")).string();
    const auto [status, output] = test_support::run_command(
        "calibrate " + recording + " --frames 150 --quiet " + options + " --out " + subject);
    EXPECT_EQ(status, 0) << output;
    std::ifstream report((dir / (name + "_report.json")).string());
    return std::make_pair(app::load_marker_set(subject), nlohmann::json::parse(report));
  };
  const auto [free_set, free_report] = calibrated("free", "--shrink 0");
  const auto [default_set, default_report] = calibrated("default", "");
  const auto [held_set, held_report] = calibrated("held", "--shrink 1000000");
  EXPECT_EQ(free_report["weak_direction_shrink"].get<double>(), 0.0);
  EXPECT_EQ(default_report["weak_direction_shrink"].get<double>(), 0.03);
  EXPECT_EQ(held_report["weak_direction_shrink"].get<double>(), 1e6);
  // Offsets in the subject files are at the set's reference height; the three calibrations share
  // the recording, the height and the lengths' freedom, so their offsets differ by the shrinkage.
  const auto largest_difference = [](const body::MarkerSet& a, const body::MarkerSet& b) {
    double largest = 0;
    for (std::size_t m = 0; m < a.entries.size(); ++m)
      largest = std::max(largest, (a.entries[m].offset - b.entries[m].offset).norm());
    return largest;
  };
  ASSERT_EQ(free_set.entries.size(), held_set.entries.size());
  EXPECT_GT(largest_difference(free_set, held_set), 5.0);
  EXPECT_GT(largest_difference(free_set, default_set), 0.1);
  const auto [bad, bad_output] = test_support::run_command("calibrate " + recording + " --shrink -1 --out " +
                                                           (dir / "bad.json").string());
  EXPECT_NE(bad, 0);
  EXPECT_NE(bad_output.find("--shrink"), std::string::npos) << bad_output;
  EXPECT_FALSE(fs::exists(dir / "bad.json"));
}

}  // namespace

namespace {

// --static calibrates a static trial in the model's zero pose (the bundled `static` motion
// simulated): the report records the posture's SD, the subject differs from the one calibrated
// without it, and a nonsensical SD is refused by name.
TEST(CalibrateCommand, StaticTrialIsCalibratedInTheZeroPose) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = fs::path(s2kf::test_support::tmp_dir()) / "static";
  fs::create_directories(dir);
  const std::string recording = (dir / "static.c3d").string();
  const auto [simulated, simulate_output] =
      test_support::run_command("simulate --motion static --seed 3 --out " + recording);
  ASSERT_EQ(simulated, 0) << simulate_output;
  const auto calibrated = [&](const std::string& name, const std::string& options) {
    const std::string subject = (dir / (name + ".json")).string();
    const auto [status, output] =
        test_support::run_command("calibrate " + recording + " --quiet " + options + " --out " + subject);
    EXPECT_EQ(status, 0) << output;
    std::ifstream report((dir / (name + "_report.json")).string());
    return std::make_pair(app::load_marker_set(subject), nlohmann::json::parse(report));
  };
  const auto [posed_set, posed_report] = calibrated("posed", "--static");
  const auto [free_set, free_report] = calibrated("free", "");
  EXPECT_EQ(posed_report["static_pose_sd_deg"].get<double>(), 3.0);
  EXPECT_TRUE(free_report["static_pose_sd_deg"].is_null());
  double largest = 0;
  for (std::size_t m = 0; m < posed_set.entries.size(); ++m)
    largest = std::max(largest, (posed_set.entries[m].offset - free_set.entries[m].offset).norm());
  EXPECT_GT(largest, 1.0);  // at the reference height, mm: the posture moved some markers
  const auto [bad, bad_output] = test_support::run_command(
      "calibrate " + recording + " --static --static-sd 0 --out " + (dir / "bad.json").string());
  EXPECT_NE(bad, 0);
  EXPECT_NE(bad_output.find("--static-sd"), std::string::npos) << bad_output;
  EXPECT_FALSE(fs::exists(dir / "bad.json"));
}

}  // namespace

namespace {

// `s2kf track REC --static STATIC --static-alone`: the subject is calibrated on the static trial
// first, written as PREFIX_subject.json, and is the one `s2kf calibrate STATIC --static` writes;
// the recording is then tracked with it as with --subject (the same accuracy against the truth).
// Without --static-alone the static trial and the recording are calibrated together, and the
// PREFIX_subject.json written then tracks the recording as that run did. Combinations that cannot
// work and a missing static trial are refused by name and leave no output.
TEST(CalibrateCommand, TrackWithAStaticTrialWritesItsSubject) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = fs::path(s2kf::test_support::tmp_dir()) / "track_static";
  fs::create_directories(dir);
  const std::string static_trial = (dir / "static.c3d").string(), walk = (dir / "walk").string();
  for (const std::string& command :
       {"simulate --motion static --seed 4 --out " + static_trial,
        "simulate --motion walk --seed 4 --frames 200 --out " + walk + ".c3d",
        "calibrate " + static_trial + " --static --quiet --out " + (dir / "subject.json").string()}) {
    const auto [status, output] = test_support::run_command(command);
    ASSERT_EQ(status, 0) << command << "\n" << output;
  }
  // Tracks the walk with `options` into dir/prefix against its truth; "" or why it failed.
  const auto track_walk = [&](const std::string& options, const std::string& prefix) {
    const auto [status, output] =
        test_support::run_command("track " + walk + ".c3d " + options + " --truth " + walk +
                                  "_truth.csv --formats csv --quiet --out " + (dir / prefix).string());
    return status == 0 ? std::string() : "exit status " + std::to_string(status) + ": " + output;
  };
  ASSERT_EQ(track_walk("--static " + static_trial + " --static-alone", "one"), "");
  ASSERT_EQ(track_walk("--subject " + (dir / "subject.json").string(), "two"), "");
  const body::MarkerSet written = app::load_marker_set(dir / "one_subject.json");
  const body::MarkerSet calibrated = app::load_marker_set(dir / "subject.json");
  ASSERT_EQ(written.entries.size(), calibrated.entries.size());
  for (std::size_t m = 0; m < written.entries.size(); ++m)
    EXPECT_LT((written.entries[m].offset - calibrated.entries[m].offset).norm(), 1e-9) << m;
  const auto truth_of = [&](const std::string& prefix) {
    std::ifstream summary((dir / (prefix + ".json")).string());
    return nlohmann::json::parse(summary)["truth"];
  };
  EXPECT_DOUBLE_EQ(truth_of("one")["segment_orientation_rms_deg"].get<double>(),
                   truth_of("two")["segment_orientation_rms_deg"].get<double>());
  // Calibrated together: a subject of its own (not the static trial's), which reproduces the run.
  ASSERT_EQ(track_walk("--static " + static_trial, "joint"), "");
  ASSERT_EQ(track_walk("--subject " + (dir / "joint_subject.json").string(), "again"), "");
  const body::MarkerSet joint_subject = app::load_marker_set(dir / "joint_subject.json");
  ASSERT_EQ(joint_subject.entries.size(), calibrated.entries.size());
  double moved = 0;
  for (std::size_t m = 0; m < joint_subject.entries.size(); ++m)
    moved = std::max(moved, (joint_subject.entries[m].offset - calibrated.entries[m].offset).norm());
  EXPECT_GT(moved, 1.0);  // mm: the walk moved some markers
  EXPECT_NE(joint_subject.description.find("on static.c3d and walk.c3d"), std::string::npos)
      << joint_subject.description;
  // To rounding, not to the bit: the file holds the offsets at the reference height and each
  // segment's length factors as one product ((x 1000 / h) h / 1000 is not x for about a quarter of
  // the coordinates), which the filter carries to about 1e-7 degrees (measured: 8.5e-8 and 3.1e-7).
  EXPECT_NEAR(truth_of("joint")["segment_orientation_rms_deg"].get<double>(),
              truth_of("again")["segment_orientation_rms_deg"].get<double>(), 1e-5);
  EXPECT_NEAR(truth_of("joint")["limb_flexion_rms_deg"].get<double>(),
              truth_of("again")["limb_flexion_rms_deg"].get<double>(), 1e-5);

  const auto refused = [&](const std::string& options, const std::string& prefix) {
    const auto [status, output] = test_support::run_command("track " + walk + ".c3d " + options +
                                                            " --quiet --out " + (dir / prefix).string());
    EXPECT_NE(status, 0) << options;
    EXPECT_NE(output.find("--static"), std::string::npos) << output;
    EXPECT_FALSE(fs::exists(dir / (prefix + ".json"))) << options;
    EXPECT_FALSE(fs::exists(dir / (prefix + "_subject.json"))) << options;
  };
  refused("--static " + static_trial + " --subject " + (dir / "subject.json").string(), "both");
  refused("--static " + static_trial + " --no-calibrate", "uncalibrated");
  refused("--static-alone", "alone_without_static");
  refused("--static " + (dir / "missing.c3d").string(), "missing");
  // A recording that fails after the static trial was calibrated leaves no subject file either.
  const std::string empty = (dir / "empty.c3d").string();
  std::ofstream(empty).close();
  for (const char* alone : {"", " --static-alone"}) {
    const auto [failed, failed_output] =
        test_support::run_command("track " + empty + " --static " + static_trial + alone + " --quiet --out " +
                                  (dir / "failed").string());
    EXPECT_NE(failed, 0);
    EXPECT_NE(failed_output.find("empty"), std::string::npos) << failed_output;
    EXPECT_FALSE(fs::exists(dir / "failed_subject.json")) << alone;
    EXPECT_FALSE(fs::exists(dir / "failed.json")) << alone;
  }
}

}  // namespace
