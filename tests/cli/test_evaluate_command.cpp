// The `s2kf evaluate` command: its results folder, its numbers against the library's, the true-
// subject reference of a simulated motion, and the sentences bad input gets.
//
// Sizes are small on purpose (60 frames, L = 93, 2 runs): the suite also runs under sanitizers.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/evaluation/evaluation.hpp>
#include <s2kf/evaluation/true_subject_reference.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/sim/occlusion.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>
#include <s2kf/track/gradient_baseline.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/tracking_run.hpp>

#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/app/motion_json.hpp>

#include "cli_runner.hpp"

#include "test_files.hpp"
#include "tracked_recording.hpp"
#include "tracker_samples.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>
#include "address_sanitizer.hpp"

namespace {

using namespace s2kf;
namespace fs = std::filesystem;
using namespace test_support;

using test_support::CommandResult;
using test_support::run_command;

/// The number after "key": at its first occurrence after `after` in a JSON text.
double json_number(const std::string& text, const std::string& key, const std::string& after = "") {
  const std::size_t start = after.empty() ? 0 : text.find("\"" + after + "\"");
  const std::size_t at = text.find("\"" + key + "\":", start == std::string::npos ? 0 : start);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(text.c_str() + at + key.size() + 3, nullptr);
}

MarkerSequence bundled_handstand(Eigen::Index frames) {
  const MarkerSequence all = c3d::read_c3d(data_file("handstand.c3d"));
  return all.frames(0, std::min(frames, all.frame_count()));
}

TEST(EvaluateCommand, ShortRunWritesTheResultsFolder) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path out = empty_scratch("evaluate_short");
  const CommandResult result =
      run_command("evaluate --frames 60 --runs 2 --samples 93 --no-calibrate --quiet --out " + out.string());
  ASSERT_EQ(result.status, 0) << result.output;
  for (const char* name : {"marker_distance.csv", "occlusion_band.csv", "hidden_markers.csv", "runtime.csv",
                           "joint_error.csv", "samples.csv", "summary.json"})
    EXPECT_TRUE(fs::exists(out / name)) << name;
  const std::string summary = read_text(out / "summary.json");
  if (summary.find("\"figure_problems\": []") != std::string::npos)
    for (const char* name :
         {"fig3_marker_distance", "fig4_runtime", "fig7_hidden_markers", "joint_error", "samples"}) {
      EXPECT_GT(fs::file_size(out / (std::string(name) + ".png")), 1000u) << name;
      EXPECT_GT(fs::file_size(out / (std::string(name) + ".svg")), 1000u) << name;
    }
  // 60 frames: a header and 60 rows per series.
  const std::string distance = read_text(out / "marker_distance.csv");
  EXPECT_EQ(std::count(distance.begin(), distance.end(), '\n'), 61);
  EXPECT_EQ(distance.substr(0, distance.find('\n')), "frame,time,s2kf_mm,baseline_mm");
  const std::string hidden = read_text(out / "hidden_markers.csv");
  EXPECT_EQ(hidden.substr(0, hidden.find('\n')), "frame,time,run1,run2,mean");

  // The numbers are the library's for the same input.
  const MarkerSequence recording = bundled_handstand(60);
  const pipeline::Session setup = evaluation_session(recording);
  const io::MotionTable truth =
      evaluation::first_rows(io::load_motion_csv(data_file("handstand_truth.csv")), 60);
  const evaluation::MethodResult s2kf =
      evaluation::evaluate_method(setup, recording, pipeline::Method::s2kf, 93, &truth, 20);
  const evaluation::MethodResult baseline =
      evaluation::evaluate_method(setup, recording, pipeline::Method::baseline, 0, &truth, 20);
  EXPECT_NEAR(json_number(summary, "mean_marker_distance_mm", "s2kf"), s2kf.level_mm, 1e-9 * s2kf.level_mm);
  EXPECT_NEAR(json_number(summary, "mean_marker_distance_mm", "baseline"), baseline.level_mm,
              1e-9 * baseline.level_mm);
  EXPECT_NEAR(json_number(summary, "segment_orientation_rms_deg", "s2kf"),
              s2kf.truth->segment_orientation_rms_deg, 1e-9);
  const nlohmann::json parsed = nlohmann::json::parse(summary);
  EXPECT_EQ(parsed["frames"], 60);
  EXPECT_EQ(parsed["occlusion"]["runs"], 2);
  // Prepared as s2kf track prepares it: the bundled set chosen by the labels, not calibrated here.
  EXPECT_NE(summary.find("\"marker_set\": \"kit\""), std::string::npos);
  EXPECT_NE(summary.find("\"calibrated\": false"), std::string::npos);
}

TEST(EvaluateCommand, BadInputGivesASentenceAndExitStatusOne) {
  const fs::path dir = empty_scratch("evaluate_bad");
  auto expect_failure = [&](const std::string& arguments, const std::string& phrase) {
    const CommandResult result =
        run_command("evaluate " + arguments + " --quiet --out " + (dir / "out").string());
    EXPECT_EQ(result.status, 1) << arguments << "\n" << result.output;
    EXPECT_NE(result.output.find("s2kf: "), std::string::npos) << result.output;
    EXPECT_NE(result.output.find(phrase), std::string::npos) << arguments << "\n" << result.output;
  };
  expect_failure((dir / "missing.c3d").string(), "no such file");
  expect_failure("--samples 93,abc --frames 5", "'abc' is not one");
  expect_failure("--samples 5 --frames 5", "'5' is not one");
  expect_failure("--samples 93, --frames 5", "comma-separated");
  // Truth with other columns, and truth with too few frames.
  {
    std::ofstream bad(dir / "columns.csv");
    bad << "frame,time,root_x,root_y,root_z,root_roll,root_pitch,root_yaw,elbow\n0,0,0,0,0,0,0,0,0\n";
  }
  expect_failure(data_file("handstand.c3d") + " --frames 5 --truth " + (dir / "columns.csv").string(),
                 "joint columns");
  {
    std::ifstream in(data_file("handstand_truth.csv"));
    std::ofstream shortened(dir / "short.csv");
    std::string line;
    for (int i = 0; i < 11 && std::getline(in, line); ++i) shortened << line << "\n";
  }
  expect_failure(data_file("handstand.c3d") + " --frames 5 --truth " + (dir / "short.csv").string(),
                 "has 10 frames");
  // A simulated recording: the motion must exist and excludes a recording and its truth.
  expect_failure("--motion no_such_motion --frames 5", "unknown motion 'no_such_motion'");
  expect_failure(data_file("handstand.c3d") + " --motion walk --frames 5", "give no recording");
  expect_failure("--motion walk --occlusion 2,10 --frames 5", "probability p must lie in [0, 1]");
  expect_failure(data_file("handstand.c3d") + " --occlusion 0.005,100 --frames 5", "simulated --motion only");
}

// --motion simulates a realistic subject and reports the true-subject fit beside the S2KF; the
// numbers are the library's for the same subject and recording.
TEST(EvaluateCommand, SimulatedMotionReportsTheTrueSubjectReference) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path out = empty_scratch("evaluate_motion");
  const CommandResult result = run_command(
      "evaluate --motion walk --subject-seed 2 --frames 80 --runs 1 --samples 93 --no-calibrate --smooth "
      "--out " +
      out.string());
  ASSERT_EQ(result.status, 0) << result.output;
  EXPECT_NE(result.output.find("(true-subject fit "), std::string::npos) << result.output;
  const std::string summary = read_text(out / "summary.json");
  // The library's reference on the same subject and recording.
  const sim::SubjectOptions options;
  const sim::Subject subject = sim::make_subject(body::mmm_body_model(options.height_mm), options, 2);
  const app::JointTable joints{subject.joint_names, subject.lower, subject.upper};
  sim::RecordingOptions recording_options;
  recording_options.frames = 80;
  const sim::Recording recording = sim::simulate_recording(
      app::load_motion_file(data_file("motions/walk.json"), joints, 2), subject, recording_options, 2);
  const evaluation::TruthComparison expected =
      evaluation::compare_with_truth(subject.model, evaluation::true_subject_fit(subject, recording),
                                     sim::truth_motion(recording, subject.joint_names), 20);
  const double reference = json_number(summary, "segment_orientation_rms_deg", "true_subject_reference");
  EXPECT_NEAR(reference, expected.segment_orientation_rms_deg, 1e-6);
  EXPECT_GT(reference, 0.1);
  EXPECT_LT(reference, json_number(summary, "segment_orientation_rms_deg", "s2kf"));  // it knows the subject
  EXPECT_GT(json_number(summary, "segment_orientation_rms_deg", "s2kf_smoothed"), 0.1);
  EXPECT_EQ(nlohmann::json::parse(summary)["frames"], 80);
  // The identifiable-subject references: at the exact gauges, a looser threshold and the nominal.
  // Without calibration the tracker's model is the nominal one, so the fit with the tracker's model
  // and the "nominal" reference are the same fit.
  const nlohmann::json parsed = nlohmann::json::parse(summary);
  const nlohmann::json& identifiable = parsed["identifiable_subject_reference"];
  ASSERT_EQ(identifiable.size(), 3u);
  EXPECT_EQ(identifiable[0]["prior_only_fraction"], 1e-5);
  EXPECT_EQ(identifiable[2]["prior_only_fraction"], "nominal");
  EXPECT_EQ(identifiable[2]["reset_directions"], identifiable[2]["subject_unknowns"]);
  EXPECT_LE(identifiable[0]["reset_directions"].get<int>(), identifiable[1]["reset_directions"].get<int>());
  EXPECT_NEAR(identifiable[2]["truth"]["segment_orientation_rms_deg"].get<double>(),
              parsed["tracker_model_reference"]["segment_orientation_rms_deg"].get<double>(), 1e-9);
  EXPECT_GT(identifiable[0]["truth"]["segment_orientation_rms_deg"].get<double>(), 0.1);
  // The best constant placement: the library's, on the same subject and recording; and its
  // identifiable part, whose gauges go back to the marker set's, is no better.
  const evaluation::TruthComparison constant = evaluation::compare_with_truth(
      subject.model,
      evaluation::true_subject_fit(evaluation::best_constant_placement(subject, recording), recording),
      sim::truth_motion(recording, subject.joint_names), 20);
  const nlohmann::json& placement = parsed["constant_placement_reference"];
  EXPECT_NEAR(placement["truth"]["segment_orientation_rms_deg"].get<double>(),
              constant.segment_orientation_rms_deg, 1e-6);
  EXPECT_EQ(placement["identifiable"]["prior_only_fraction"], 1e-5);
  EXPECT_GT(placement["identifiable"]["reset_directions"].get<int>(), 0);
  EXPECT_GT(placement["identifiable"]["truth"]["segment_orientation_rms_deg"].get<double>(),
            placement["truth"]["segment_orientation_rms_deg"].get<double>());
  // The calibration's bundle adjustment at the true poses: it fits the markers far better than
  // the marker set does.
  const nlohmann::json& at_true_poses = parsed["calibration_at_true_poses_reference"];
  EXPECT_GT(at_true_poses["frames_used"].get<int>(), 5);
  EXPECT_LT(at_true_poses["bundle_rms_after_mm"].get<double>(),
            0.5 * at_true_poses["bundle_rms_before_mm"].get<double>());
  EXPECT_GT(at_true_poses["truth"]["segment_orientation_rms_deg"].get<double>(), 0.1);
  // The tracker with the subject the simulation drew: the library's S2KF on the session evaluate
  // prepares (the marker set its labels choose, no calibration), with the true model in its place.
  pipeline::Session session;
  {
    SequenceFrameSource source(recording);
    pipeline::SessionOptions session_options;
    session_options.calibrate = false;
    session = pipeline::prepare_session(source, app::choose_marker_set_for(recording.labels, "", "").set,
                                        session_options, test::tracker_samples());
  }
  session.model = subject.model;
  const io::MotionTable true_motion = sim::truth_motion(recording, subject.joint_names);
  const evaluation::MethodResult with_true_subject =
      evaluation::evaluate_method(session, recording, pipeline::Method::s2kf, 93, &true_motion, 20);
  const nlohmann::json& true_tracking = parsed["true_subject_tracking_reference"];
  EXPECT_NEAR(true_tracking["s2kf"]["segment_orientation_rms_deg"].get<double>(),
              with_true_subject.truth->segment_orientation_rms_deg, 1e-9);
  // Knowing the subject, the filter does better than with the nominal marker set.
  EXPECT_LT(true_tracking["s2kf"]["segment_orientation_rms_deg"].get<double>(),
            json_number(summary, "segment_orientation_rms_deg", "s2kf"));
  EXPECT_GT(true_tracking["s2kf_smoothed"]["segment_orientation_rms_deg"].get<double>(), 0.1);
}

}  // namespace
