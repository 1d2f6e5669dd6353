// Static trials as labs record them: the pose held is found from the data or named (--static-pose
// zero|t-pose|a-pose|FILE), and a subject no person could be (a static trial calibrated in a pose
// the subject did not hold) is refused with a sentence naming the segment or marker, exit 1, and
// no subject file.

#include "address_sanitizer.hpp"
#include "cli_runner.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "test_files.hpp"

namespace {

using namespace s2kf;
namespace fs = std::filesystem;

/// This test's own folder: ctest runs the tests side by side, and two simulating the same trial into
/// one folder would rename each other's temporary files away.
fs::path test_folder() {
  return fs::path(s2kf::test_support::tmp_dir()) / "static_pose" /
         ::testing::UnitTest::GetInstance()->current_test_info()->name();
}

/// A static trial in the T-pose (the bundled static motion, its sway included, with the upper arms
/// 90 degrees out), simulated once into `dir`.
std::string t_pose_trial(const fs::path& dir) {
  fs::create_directories(dir);
  const std::string recording = (dir / "t_pose.c3d").string();
  if (fs::exists(recording)) return recording;
  std::ifstream bundled(std::string(S2KF_SOURCE_DIR) + "/data/motions/static.json");
  nlohmann::json motion = nlohmann::json::parse(bundled);
  motion["name"] = "t_pose";
  for (nlohmann::json& key : motion["keyframes"]) {
    key["joints"]["LSy"] = 90;
    key["joints"]["RSy"] = -90;
  }
  const std::string motion_file = (dir / "t_pose.json").string();
  std::ofstream(motion_file) << motion.dump(1);
  const auto [status, output] =
      test_support::run_command("simulate --motion " + motion_file + " --seed 5 --out " + recording);
  EXPECT_EQ(status, 0) << output;
  return recording;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST(StaticTrialCommand, ThePoseHeldIsFoundFromTheData) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = test_folder();
  const std::string trial = t_pose_trial(dir);
  const auto [status, output] =
      test_support::run_command("calibrate " + trial + " --static --out " + (dir / "found.json").string());
  ASSERT_EQ(status, 0) << output;
  const nlohmann::json report = read_json(dir / "found_report.json");
  const std::string pose = report["static_pose"].get<std::string>();
  EXPECT_EQ(pose.rfind("t-pose (found from the data)", 0), 0u) << pose;
  EXPECT_NE(output.find("t-pose (found from the data)"), std::string::npos) << output;
  // Named, the same pose; and the pose file the simulator wrote (its truth, first row) as well.
  for (const std::string& named : {std::string("t-pose"), (dir / "t_pose_truth.csv").string()}) {
    const std::string subject = (dir / "named.json").string();
    const auto [named_status, named_output] = test_support::run_command(
        "calibrate " + trial + " --static --static-pose " + named + " --quiet --out " + subject);
    ASSERT_EQ(named_status, 0) << named_output;
    EXPECT_EQ(read_json(dir / "named_report.json")["static_pose"].get<std::string>().rfind(named, 0), 0u);
  }
}

// The subject stood in the T-pose; calibrated as if every frame were the zero pose, the arms'
// markers would have to sit half a metre from where the marker set puts them.
TEST(StaticTrialCommand, AWrongStanceIsRefusedAndWritesNoSubject) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = test_folder();
  const std::string trial = t_pose_trial(dir);
  const fs::path subject = dir / "wrong.json";
  const auto [status, output] = test_support::run_command(
      "calibrate " + trial + " --static --static-pose zero --static-posture exact --out " + subject.string());
  EXPECT_EQ(status, 1) << output;
  EXPECT_NE(output.find("is not a person's"), std::string::npos) << output;
  EXPECT_NE(output.find("--static-pose"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(subject));
  EXPECT_FALSE(fs::exists(dir / "wrong_report.json"));
  // The same through s2kf track --static --static-alone: nothing of the recording's is written
  // (calibrated together with the recording: TheStaticTrialAndTheRecordingAreCalibratedTogether).
  const auto [tracked, tracked_output] = test_support::run_command(
      "track " + trial + " --static " + trial +
      " --static-alone --static-pose zero --static-posture exact --out " + (dir / "tracked").string());
  EXPECT_EQ(tracked, 1) << tracked_output;
  EXPECT_NE(tracked_output.find("is not a person's"), std::string::npos) << tracked_output;
  EXPECT_FALSE(fs::exists(dir / "tracked_subject.json"));
  EXPECT_FALSE(fs::exists(dir / "tracked.csv"));
}

// A recording that is all standing still in the T-pose: s2kf track takes it as its own static trial,
// calibrated together with the recording, and says so; --no-static-stretch does not.
TEST(StaticTrialCommand, AStillStretchInsideTheRecordingIsItsStaticTrial) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = test_folder();
  const std::string trial = t_pose_trial(dir);
  const auto messages = [&](const std::string& name, const std::string& options) {
    const auto [status, output] = test_support::run_command("track " + trial + " --formats csv --quiet " +
                                                            options + " --out " + (dir / name).string());
    EXPECT_EQ(status, 0) << output;
    const nlohmann::json summary = read_json(dir / (name + ".json"));
    std::string all;
    for (const auto& message : summary["marker_set_messages"]) all += message.get<std::string>() + "\n";
    return all;
  };
  const std::string found = messages("stretch", "");
  EXPECT_NE(found.find("frames 0-299 (3.0 s) are a static trial in the t-pose (found from the data)"),
            std::string::npos)
      << found;
  EXPECT_NE(found.find("calibrated together with the recording (--no-static-stretch: not)"),
            std::string::npos)
      << found;
  EXPECT_EQ(messages("no_stretch", "--no-static-stretch").find("static trial"), std::string::npos);
}

// --static calibrates the static trial and the recording together (one bundle adjustment): the
// recording's summary says so, its calibration holds the frames of both, and a static trial in a
// stance the calibration is told wrongly is refused as with --static-alone, writing nothing. The
// former --static-refine does the same and says what replaced it.
TEST(StaticTrialCommand, TheStaticTrialAndTheRecordingAreCalibratedTogether) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = test_folder();
  const std::string trial = t_pose_trial(dir);
  const std::string walk = (dir / "walk.c3d").string();
  const auto [simulated, simulate_output] =
      test_support::run_command("simulate --motion walk --seed 5 --frames 200 --out " + walk);
  ASSERT_EQ(simulated, 0) << simulate_output;
  const auto [status, output] = test_support::run_command(
      "track " + walk + " --static " + trial + " --formats csv --quiet --out " + (dir / "joint").string());
  ASSERT_EQ(status, 0) << output;
  const nlohmann::json summary = read_json(dir / "joint.json");
  std::string messages;
  for (const auto& message : summary["marker_set_messages"]) messages += message.get<std::string>() + "\n";
  EXPECT_NE(messages.find("calibrated together with the static trial " + trial), std::string::npos)
      << messages;
  // The static trial's 301 frames come first, then the walk's 200.
  EXPECT_EQ(summary["calibration"]["frames"].get<int>(), 501) << summary["calibration"].dump();
  EXPECT_TRUE(fs::exists(dir / "joint_subject.json"));  // the recording's calibration, for --subject

  const auto [deprecated, deprecated_output] =
      test_support::run_command("track " + walk + " --static " + trial +
                                " --static-refine --formats csv --quiet --out " + (dir / "refined").string());
  ASSERT_EQ(deprecated, 0) << deprecated_output;
  EXPECT_NE(deprecated_output.find("--static-refine is deprecated: calibrating the static trial and the "
                                   "recording together is what --static does now"),
            std::string::npos)
      << deprecated_output;
  // The same motion, to the digit.
  ASSERT_TRUE(fs::exists(dir / "refined.csv"));
  EXPECT_EQ(test_support::read_text(dir / "refined.csv"), test_support::read_text(dir / "joint.csv"));

  const auto [wrong, wrong_output] = test_support::run_command("track " + walk + " --static " + trial +
                                                               " --static-pose zero --static-posture exact " +
                                                               "--out " + (dir / "joint_wrong").string());
  EXPECT_EQ(wrong, 1) << wrong_output;
  EXPECT_NE(wrong_output.find("is not a person's"), std::string::npos) << wrong_output;
  EXPECT_FALSE(fs::exists(dir / "joint_wrong.csv"));
}

// A real Plug-in Gait pair of one subject (Vicon Nexus 1.8, cadop/pyCGM): the static trial stands
// with the arms out and the elbows bent, and both trials carry 37 unidentified points that Nexus
// numbers afresh in each (*115, a head marker in the walk, is another marker in the static trial). Their
// labels do not name the same markers across the trials, so the static trial leaves them out; before, they
// broke the calibration (a pelvis bone-length factor of 3.91) and the run exited with status 1.
TEST(StaticTrialCommand, ARealPlugInGaitPairTracksWithItsStaticTrial) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = test_folder();
  fs::create_directories(dir);
  const std::string moving = std::string(S2KF_C3D_DATA_DIR) + "/PiG_Movement_trial.c3d";
  const std::string trial = std::string(S2KF_C3D_DATA_DIR) + "/PiG_Static_trial.c3d";
  const auto [status, output] = test_support::run_command(
      "track " + moving + " --static " + trial + " --formats csv --quiet --out " + (dir / "pair").string());
  ASSERT_EQ(status, 0) << output;
  const nlohmann::json pair = read_json(dir / "pair.json");
  const auto [without_status, without_output] = test_support::run_command(
      "track " + moving + " --formats csv --quiet --out " + (dir / "without").string());
  ASSERT_EQ(without_status, 0) << without_output;
  const nlohmann::json without = read_json(dir / "without.json");
  // The target: lower with the static trial than without. Measured: 4.84 mm against 4.95
  // (docs/static-trials.md, "A real pair"); 7.61 while the static trial's 498 still frames counted
  // one by one.
  EXPECT_LT(pair["mean_marker_distance_all_frames_mm"].get<double>(),
            without["mean_marker_distance_all_frames_mm"].get<double>());
  const long frames = pair["frames_tracked"].get<long>();
  for (const auto& rejected : pair["rejected_markers"])
    EXPECT_LE(rejected["innovation"].get<long>() + rejected["frozen"].get<long>(), frames / 10)
        << rejected.dump();
  std::string messages;
  for (const auto& message : pair["marker_set_messages"]) messages += message.get<std::string>() + "\n";
  EXPECT_NE(messages.find("the static trial PiG_Static_trial.c3d leaves out"), std::string::npos) << messages;
  EXPECT_NE(messages.find("*120 "), std::string::npos) << messages;
  // The named Plug-in Gait markers are the same landmarks in both trials: none is left out.
  const std::string left_out = messages.substr(messages.find("leaves out"));
  for (const char* named : {"LTHI", "LKNE", "LTIB", "RTIB", "LSHO", "RSHO"})
    EXPECT_EQ(left_out.substr(0, left_out.find('\n')).find(named), std::string::npos) << named;

  // Alone, the static trial (straight legs) places the knees along them unlike any person's: thighs
  // 0.79 and 1.04. Refused with the cause, and no subject file.
  const auto [refused, refused_output] =
      test_support::run_command("calibrate " + trial + " --static --out " + (dir / "static.json").string());
  EXPECT_EQ(refused, 1) << refused_output;
  EXPECT_NE(refused_output.find("segments LH and RH came out"), std::string::npos) << refused_output;
  EXPECT_NE(refused_output.find("the limbs were straight"), std::string::npos) << refused_output;
  EXPECT_FALSE(fs::exists(dir / "static.json"));
}

// A static trial that is no C3D file stops the run in one sentence naming it, before any output
// (the marker set inferred for the recording's unnamed markers included).
TEST(StaticTrialCommand, AnUnreadableStaticTrialWritesNothing) {
  const std::string moving = std::string(S2KF_C3D_DATA_DIR) + "/PiG_Movement_trial.c3d";
  const std::string empty = std::string(S2KF_C3D_DATA_DIR) + "/Empty.c3d";
  // Calibrated together with the recording, and alone (the recording's unnamed markers are placed
  // first, which writes the completed set: not before the static trial is known to be readable).
  for (const std::string alone : {"", " --static-alone"}) {
    const fs::path dir = test_folder();
    fs::remove_all(dir);
    fs::create_directories(dir);
    const auto [status, output] = test_support::run_command("track " + moving + " --static " + empty + alone +
                                                            " --quiet --out " + (dir / "run").string());
    EXPECT_EQ(status, 1) << alone << output;
    EXPECT_NE(output.find("--static: Empty.c3d: not a C3D file: the file is empty"), std::string::npos)
        << alone << output;
    EXPECT_TRUE(fs::is_empty(dir)) << alone << fs::directory_iterator(dir)->path();
  }
}

TEST(StaticTrialCommand, AnUnknownPoseIsRefusedByName) {
  const fs::path dir = fs::path(s2kf::test_support::tmp_dir()) / "static_pose_unknown";
  fs::create_directories(dir);
  const std::string recording = std::string(S2KF_DATA_DIR) + "/walk.c3d";
  const auto [status, output] = test_support::run_command(
      "calibrate " + recording + " --static --static-pose y-pose --out " + (dir / "s.json").string());
  EXPECT_EQ(status, 1) << output;
  EXPECT_NE(output.find("'y-pose' is neither zero, t-pose, a-pose nor an existing pose CSV"),
            std::string::npos)
      << output;
  EXPECT_FALSE(fs::exists(dir / "s.json"));
}

}  // namespace
