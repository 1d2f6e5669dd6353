// The `s2kf track` command: the same motion as the library, the files it writes, calibration,
// accuracy against a truth, figures, batches, bad input and constant memory.
//
// Thresholds: measured on the bundled recordings (docs/tracking.md gives the numbers), with about
// 30 % margin for a change of seed or sample set; a wrong formula (a sign, an axis order, a missing
// re-centring) moves these errors by far more.
#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/calibration/height_estimate.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/bvh.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/c3d_writer.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/io/motion_stream_writer.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracking_metrics.hpp>
#include <s2kf/track/tracking_run.hpp>

#include "cli_runner.hpp"

#include <nlohmann/json.hpp>

#include "test_files.hpp"
#include "tracked_recording.hpp"
#include "tracker_samples.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>

#include "address_sanitizer.hpp"

namespace {

using namespace s2kf;
namespace fs = std::filesystem;
using namespace test_support;

using test_support::CommandResult;
using test_support::run_command;

TEST(TrackCommand, AgreesWithTheLibraryAndWritesFilesThatParse) {
  const fs::path out = scratch("cli") / "hs";
  // --no-calibrate: the library run below tracks with the model as it is.
  const CommandResult r =
      run_command("track " + data_file("handstand.c3d") + " --no-calibrate --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("tracked 675 of 675 frames"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("marker set kit (chosen automatically"), std::string::npos) << r.output;

  const auto cli = io::load_motion_csv(out.string() + ".csv");
  const auto recording = c3d::read_c3d(data_file("handstand.c3d"));
  const Tracked lib = track_recording(recording, io::load_motion_csv(data_file("handstand_truth.csv")));
  ASSERT_EQ(cli.frames(), lib.run.motion.frames());
  EXPECT_EQ(cli.joint_names, lib.run.motion.joint_names);
  EXPECT_LT((cli.values - lib.run.motion.values).cwiseAbs().maxCoeff(), 1e-5);  // %.9g round trip

  std::ifstream json(out.string() + ".json");
  std::stringstream text;
  text << json.rdbuf();
  for (const char* key : {"\"frames\"", "\"frames_tracked\"", "\"markers_used\"", "\"labels_ignored\"",
                          "\"mean_marker_distance_mm\"", "\"converged_frame\"", "\"latency_ms\"",
                          "\"median\"", "\"p99\"", "\"samples\"", "\"warnings\""})
    EXPECT_NE(text.str().find(key), std::string::npos) << key;

  std::ifstream mot(out.string() + ".mot");
  std::string line;
  std::getline(mot, line);
  EXPECT_EQ(line, "handstand");
  bool header_done = false;
  while (std::getline(mot, line))
    if (line == "endheader") {
      header_done = true;
      break;
    }
  ASSERT_TRUE(header_done);
  std::getline(mot, line);
  EXPECT_EQ(line.rfind("time\troot_x\t", 0), 0u);
  long rows = 0;
  while (std::getline(mot, line)) ++rows;
  EXPECT_EQ(rows, 675);

  std::ifstream bvh(out.string() + ".bvh");
  std::stringstream b;
  b << bvh.rdbuf();
  const std::string s = b.str();
  EXPECT_EQ(s.rfind("HIERARCHY\nROOT pelvis", 0), 0u);
  EXPECT_NE(s.find("Frames: 675\n"), std::string::npos);
  const auto frame_time = s.find("Frame Time: ");
  ASSERT_NE(frame_time, std::string::npos);
  EXPECT_NEAR(std::stod(s.substr(frame_time + 12)), 0.01, 1e-12);
  // 6 root channels + 3 per joint group (16 groups) values per frame line.
  const auto motion_at = s.find("Frame Time:");
  const auto first_frame = s.find('\n', motion_at) + 1;
  std::istringstream values(s.substr(first_frame, s.find('\n', first_frame) - first_frame));
  int channels = 0;
  for (double v; values >> v;) ++channels;
  int declared = 0;
  for (auto at = s.find("CHANNELS "); at != std::string::npos; at = s.find("CHANNELS ", at + 1))
    declared += std::stoi(s.substr(at + 9));
  EXPECT_EQ(channels, declared);
  EXPECT_EQ(declared, 6 + 3 * 16);

  std::ifstream markers(out.string() + "_markers.csv");
  std::getline(markers, line);
  EXPECT_EQ(line, "frame,time,mean_marker_distance_mm,visible_markers");

  // The program streams its outputs; they are byte for byte what the batch writers make of the
  // library's run (the same model and frames, so the same numbers).
  const fs::path batch = scratch("cli") / "hs_batch";
  io::save_motion_csv(batch.string() + ".csv", lib.run.motion);
  io::save_opensim_mot(batch.string() + ".mot", lib.run.motion, "handstand");
  io::save_bvh(batch.string() + ".bvh", lib.model, lib.run.motion, recording.info.rate);
  for (const char* ext : {".csv", ".mot", ".bvh"})
    EXPECT_TRUE(read_text(out.string() + ext) == read_text(batch.string() + ext)) << ext << " differs";
  std::ostringstream report;  // the marker report as the program wrote it before it streamed
  report << "frame,time,mean_marker_distance_mm,visible_markers\n" << std::setprecision(9);
  for (std::size_t f = 0; f < lib.run.motion.frame.size(); ++f) {
    report << lib.run.motion.frame[f] << "," << lib.run.motion.time[f] << ",";
    if (std::isfinite(lib.run.mean_marker_distance[f]))
      report << lib.run.mean_marker_distance[f];
    else
      report << "nan";
    report << "," << lib.run.visible_markers[f] << "\n";
  }
  EXPECT_TRUE(read_text(out.string() + "_markers.csv") == report.str()) << "_markers.csv differs";
  for (const auto& entry : fs::directory_iterator(out.parent_path()))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST(TrackCommand, BadInputGivesASentenceAndNonZeroExit) {
  const fs::path out = empty_scratch("bad") / "x";
  CommandResult r = run_command("track /nonexistent/file.c3d --out " + out.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("no such file"), std::string::npos) << r.output;
  r = run_command("track " + std::string(S2KF_C3D_DATA_DIR) + "/Empty.c3d --out " + out.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("empty"), std::string::npos) << r.output;
  // Dance's markers (c3d.org sample13, labels Channel1nn) ride rigidly on no segment of the body.
  r = run_command("track " + std::string(S2KF_C3D_DATA_DIR) + "/Dance.c3d --out " + out.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("belongs to a bundled marker set"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("ride rigidly on no segment"), std::string::npos) << r.output;
  r = run_command("track " + data_file("handstand.c3d") + " --samples 1 --out " + out.string());
  EXPECT_NE(r.status, 0);
  EXPECT_FALSE(fs::exists(out.string() + ".csv"));
  EXPECT_FALSE(fs::exists(out.string() + ".csv.tmp"));
  r = run_command("track " + data_file("handstand.c3d") + " --smooth --method baseline --out " +
                  out.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("--smooth"), std::string::npos) << r.output;
  r = run_command("track " + data_file("handstand.c3d") + " --markerset cmu --subject x.json --out " +
                  out.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("not both"), std::string::npos) << r.output;
  r = run_command("track " + data_file("handstand.c3d") + " --markerset nosuchset --out " + out.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("nosuchset"), std::string::npos) << r.output;
  r = run_command("track " + data_file("handstand.c3d") + " --subject /nonexistent/subject.json --out " +
                  out.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out.string() + ".csv"));
}

TEST(TrackCommand, CalibratesByDefaultAndLowersTheMarkerDistance) {
  S2KF_SKIP_UNDER_SANITIZERS();
  // The handstand, not the walk: while walking, the random-walk prediction's lag (up to ~25 mm)
  // dominates the marker distance whatever the subject model.
  const fs::path out = scratch("calibrated") / "handstand";
  const CommandResult r =
      run_command("track " + data_file("handstand.c3d") + " --calibration-frames 300 --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("calibrated on 300 frames"), std::string::npos) << r.output;
  const std::string summary = read_text(out.string() + ".json");
  EXPECT_NE(summary.find("\"mean_marker_distance_after_mm\""), std::string::npos) << summary;
  // The calibrated subject fits the markers better than the marker set as shipped.
  const auto number_after = [&](const std::string& key) {
    const auto at = summary.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << key;
    return at == std::string::npos ? 0.0 : std::stod(summary.substr(at + key.size() + 4));
  };
  EXPECT_LT(number_after("mean_marker_distance_after_mm"),
            0.8 * number_after("mean_marker_distance_before_mm"));
  EXPECT_EQ(number_after("weak_direction_shrink"), 0.03);  // the default, recorded
  EXPECT_EQ(nlohmann::json::parse(summary)["calibration"]["samples"].get<int>(), 301);  // the tracker's
  // Each calibrated marker's noise follows its residual: 0.5 to 2 times the common 10 mm, not all alike.
  const nlohmann::json noise = nlohmann::json::parse(summary)["calibration"]["marker_noise_mm"];
  EXPECT_GE(noise.size(), 30u) << noise.dump();
  double smallest = 1e9, largest = 0;
  for (const auto& [name, sd] : noise.items()) {
    smallest = std::min(smallest, sd.get<double>());
    largest = std::max(largest, sd.get<double>());
  }
  EXPECT_GE(smallest, 5.0);
  EXPECT_LE(largest, 20.0);
  EXPECT_GT(largest, 1.2 * smallest);
  // --calibration-shrink 0 estimates every direction the data see freely: another subject, here
  // also with a calibration pass of its own sample count.
  const fs::path free = scratch("calibrated") / "free";
  const CommandResult unshrunk = run_command("track " + data_file("handstand.c3d") +
                                             " --calibration-frames 300 --calibration-shrink 0 "
                                             "--calibration-samples 93 --uniform-noise --formats csv --out " +
                                             free.string());
  ASSERT_EQ(unshrunk.status, 0) << unshrunk.output;
  const auto free_summary = nlohmann::json::parse(read_text(free.string() + ".json"));
  EXPECT_EQ(free_summary["calibration"]["weak_direction_shrink"].get<double>(), 0.0);
  EXPECT_EQ(free_summary["calibration"]["samples"].get<int>(), 93);
  EXPECT_TRUE(free_summary["calibration"]["marker_noise_mm"].empty());  // --uniform-noise
  EXPECT_NE(free_summary["calibration"]["segment_scale"].dump(),
            nlohmann::json::parse(summary)["calibration"]["segment_scale"].dump());
}

TEST(TrackCommand, EachGainIsRecordedAndTracksTheRecording) {
  S2KF_SKIP_UNDER_SANITIZERS();
  // The two gains on the handstand, without calibration: each tracks every frame, the summary
  // names it, and the information form stays within 5 % of the square-root update's marker
  // distance (measured: 21.4 mm square-root, 20.8 mm information form; a wrong gain drifts off by
  // far more).
  std::map<std::string, double> distance;
  for (const std::string gain : {"square-root", "information-form"}) {
    const fs::path out = scratch("gains") / gain;
    const CommandResult r =
        run_command("track " + data_file("handstand.c3d") + " --no-calibrate --formats csv --gain " + gain +
                    " --out " + out.string());
    ASSERT_EQ(r.status, 0) << r.output;
    const auto summary = nlohmann::json::parse(read_text(out.string() + ".json"));
    EXPECT_EQ(summary["gain"].get<std::string>(), gain);
    EXPECT_EQ(summary["frames_tracked"].get<int>(), summary["frames"].get<int>()) << gain;
    distance[gain] = summary["mean_marker_distance_all_frames_mm"].get<double>();
  }
  EXPECT_LT(distance["square-root"], 30.0);
  EXPECT_NEAR(distance["information-form"], distance["square-root"], 0.05 * distance["square-root"]);
}

TEST(TrackCommand, ARemovedGainSaysWhatReplacedIt) {
  // --gain information-form-root-products was an option; it stops before reading anything, with a
  // sentence naming the gain to use instead, and writes nothing.
  const fs::path out = scratch("removed_gain") / "h";
  const CommandResult r = run_command("track " + data_file("handstand.c3d") +
                                      " --gain information-form-root-products --out " + out.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("the gain 'information-form-root-products' was removed"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("use 'square-root'"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out.string() + ".json"));
}

TEST(TrackCommand, ReportsTheAccuracyAgainstAGivenTruth) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path out = scratch("truth") / "walk";
  CommandResult r = run_command("track " + data_file("walk.c3d") + " --no-calibrate --truth " +
                                data_file("walk_truth.csv") + " --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("Against the truth (frames 20 on): all-joint RMS"), std::string::npos) << r.output;
  // The summary's numbers are the library's comparison of the written motion with the truth.
  const auto summary = nlohmann::json::parse(read_text(out.string() + ".json"));
  const evaluation::TruthComparison t =
      evaluation::compare_with_truth(body::mmm_body_model(1750), io::load_motion_csv(out.string() + ".csv"),
                                     io::load_motion_csv(data_file("walk_truth.csv")), 20);
  ASSERT_TRUE(summary.contains("truth")) << summary.dump(2);
  EXPECT_EQ(summary["truth"]["all_joint_rms_deg"].get<double>(), t.all_joint_rms_deg);
  EXPECT_EQ(summary["truth"]["limb_flexion_rms_deg"].get<double>(), t.limb_flexion_rms_deg);
  EXPECT_EQ(summary["truth"]["frames_compared"].get<long>(), 551 - 20);
  EXPECT_GT(t.all_joint_rms_deg, 1.0);
  EXPECT_LT(t.all_joint_rms_deg, 20.0);
  // A truth of another recording is refused before tracking, with both lengths named.
  r = run_command("track " + data_file("walk.c3d") + " --no-calibrate --truth " +
                  data_file("handstand_truth.csv") + " --out " + (scratch("truth") / "wrong").string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("has 675 rows, but"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(scratch("truth") / "wrong.csv"));
}

TEST(TrackCommand, TracksWithACalibratedSubjectFileAndSmooths) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = scratch("subject");
  CommandResult r =
      run_command("calibrate " + data_file("walk.c3d") + " --frames 200 --iterations 1 --quiet --out " +
                  (dir / "walker.json").string());
  ASSERT_EQ(r.status, 0) << r.output;
  r = run_command("track " + data_file("walk.c3d") + " --subject " + (dir / "walker.json").string() +
                  " --smooth --out " + (dir / "walk").string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("subject file"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Motion smoothed"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("calibrated on"), std::string::npos)
      << r.output;  // the subject is calibrated already
  const std::string summary = read_text((dir / "walk").string() + ".json");
  EXPECT_NE(summary.find("\"smoothed\": true"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"height_source\": \"from the marker-set file\""), std::string::npos) << summary;
  const auto motion = io::load_motion_csv((dir / "walk").string() + ".csv");
  const auto truth = io::load_motion_csv(data_file("walk_truth.csv"));
  ASSERT_EQ(motion.frames(), truth.frames());
  const body::BodyModel model = body::mmm_body_model(1750);
  const evaluation::TruthComparison t = evaluation::compare_with_truth(model, motion, truth, 20);
  EXPECT_EQ(t.joint_limit_violations, 0);
  EXPECT_LT(t.limb_flexion_rms_deg, 4.0);  // measured 2.7 with the marker set alone, smoothed
}

TEST(TrackCommand, TooShortToCalibrateTracksWithTheMarkerSetAndSaysSo) {
  const std::string base = simulate_with_program("short_walk", "--motion walk --frames 15");
  const fs::path out = scratch("short") / "short_walk";
  const CommandResult r = run_command("track " + base + ".c3d --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("tracked 15 of 15 frames"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("calibrated on"), std::string::npos) << r.output;
  const std::string summary = read_text(out.string() + ".json");
  EXPECT_NE(summary.find("subject not calibrated"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"calibration\": null"), std::string::npos) << summary;
}

TEST(TrackCommand, DrawsATrackedFrame) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path out = scratch("figure") / "walk";
  CommandResult r =
      run_command("track " + data_file("walk.c3d") + " --no-calibrate --figure 200 --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  // Four blocks: 50 recorded markers, 50 model markers, the bones, 50 residual lines.
  std::ifstream in(out.string() + "_frame200.csv");
  std::string line;
  std::vector<int> rows_per_block(1, 0);
  int blank = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') {
      if (line.empty() && ++blank == 2) rows_per_block.push_back(0);
      continue;
    }
    blank = 0;
    ++rows_per_block.back();
    double x, y, z;
    char c1, c2;
    std::istringstream values(line);
    ASSERT_TRUE(values >> x >> c1 >> y >> c2 >> z) << line;
    EXPECT_LT(std::abs(z), 3000) << line;
  }
  ASSERT_EQ(rows_per_block.size(), 4u);
  EXPECT_EQ(rows_per_block[0], 50);
  EXPECT_EQ(rows_per_block[1], 50);
  EXPECT_GT(rows_per_block[2], 2 * 15);  // two points per bone
  EXPECT_EQ(rows_per_block[3], 2 * 50);
  if (std::system("command -v gnuplot > /dev/null 2>&1") == 0) {
    EXPECT_GT(fs::file_size(out.string() + "_frame200.png"), 10000u);
    EXPECT_NE(r.output.find("the figure"), std::string::npos) << r.output;
  }
  r = run_command("track " + data_file("walk.c3d") + " --figure 100000 --out " + out.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("beyond its 551 frames"), std::string::npos) << r.output;
}

TEST(TrackCommand, TracksSeveralRecordingsIntoADirectory) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path out = scratch("batch");
  const CommandResult r = run_command("track " + data_file("walk.c3d") + " " + data_file("cartwheel.c3d") +
                                      " --jobs 2 --quiet --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "walk.csv"));
  EXPECT_TRUE(fs::exists(out / "cartwheel.bvh"));
}

// The bundled handstand's frames repeated from its start up to `frames` frames, as a C3D file in
// `dir`; edit(f, positions) may change frame f.
std::string repeated_handstand(const fs::path& dir, const std::string& name, long frames,
                               const std::function<void(long, Eigen::Matrix3Xd&)>& edit = {}) {
  const c3d::Recording handstand = c3d::read_c3d(data_file("handstand.c3d"));
  std::vector<std::string> labels;
  for (const auto& label : handstand.info.labels) labels.push_back(label.raw);
  const std::string path = (dir / (name + ".c3d")).string();
  c3d::C3dStreamWriter writer(path, labels, handstand.info.rate);
  for (long f = 0; f < frames; ++f) {
    Eigen::Matrix3Xd positions = handstand.frame(f % handstand.frame_count());
    if (edit) edit(f, positions);
    writer.append(positions, handstand.visible.col(f % handstand.frame_count()));
  }
  writer.finish();
  return path;
}

// Runs the s2kf program (no shell, output discarded); its exit status and peak resident set size
// (kB) as wait4() reports them for that one child.
[[maybe_unused]] std::pair<int, long> run_for_peak_memory(const std::vector<std::string>& arguments) {
  std::vector<std::string> words{S2KF_CLI};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  const pid_t child = fork();
  if (child == 0) {
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, STDOUT_FILENO);
    dup2(null, STDERR_FILENO);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  if (child < 0 || wait4(child, &status, 0, &usage) != child) return {-1, 0};
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, usage.ru_maxrss};
}

TEST(TrackCommand, BadCoordinatesMidFileLeaveNoOutputAndNoTemporary) {
  const fs::path dir = empty_scratch("stream_bad");
  const std::string input = repeated_handstand(dir, "bad", 400, [](long f, Eigen::Matrix3Xd& positions) {
    if (f == 300) positions(0, 3) = 2e6;  // 2 km
  });
  const CommandResult r = run_command("track " + input + " --no-calibrate --height 1750 --samples 93 --out " +
                                      (dir / "out" / "bad").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("frame 300"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("beyond a kilometre"), std::string::npos) << r.output;
  EXPECT_TRUE(file_names(dir / "out").empty());
}

TEST(TrackCommand, MemoryDoesNotGrowWithTheLengthOfTheRecording) {
#if defined(S2KF_TEST_UNDER_ASAN)
  GTEST_SKIP() << "AddressSanitizer's shadow memory and quarantine make resident set sizes meaningless";
#else
  // 6000 more frames: the motion table kept in memory grew by about 780 bytes a frame (4.5 MB here);
  // streamed, only the 16 bytes a frame of the summary's series remain (0.1 MB).
  const fs::path dir = empty_scratch("stream_memory");
  const std::string short_input = repeated_handstand(dir, "short", 675);
  const std::string long_input = repeated_handstand(dir, "long", 6675);
  const auto track = [&](const std::string& input, const std::string& name) {
    return run_for_peak_memory(
        {"track", input, "--no-calibrate", "--samples", "93", "--quiet", "--out", (dir / name).string()});
  };
  const auto [short_status, short_kb] = track(short_input, "short");  // first: it may fill the sample cache
  const auto [long_status, long_kb] = track(long_input, "long");
  ASSERT_EQ(short_status, 0);
  ASSERT_EQ(long_status, 0);
  EXPECT_GT(short_kb, 0);
  EXPECT_LT(long_kb - short_kb, 1536)
      << "peak RSS " << short_kb << " kB for 675 frames, " << long_kb << " kB for 6675 frames";
  EXPECT_EQ(std::count(std::istreambuf_iterator<char>(std::ifstream(dir / "long.csv").rdbuf()), {}, '\n'),
            6676);
#endif
}

/// A real lower-body recording (c3d.org's Motion Analysis gait sample, labels such as R.ASIS,
/// L.Knee): the program picks the lower-body set, places the other markers by their motion, and
/// marks the one segment no marker rides on as not observed in the CSV, the summary and the
/// segment report.
TEST(PartialMarkerSets, ProgramMarksTheUnobservedBodyInEveryOutput) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = fs::path(s2kf::test_support::tmp_dir()) / "partial";
  fs::create_directories(dir);
  const std::string prefix = (dir / "walk1").string();
  const auto [status, output] = test_support::run_command(
      "track " + std::string(S2KF_C3D_DATA_DIR) + "/Walk1.c3d --quiet --formats csv,mot --out " + prefix);
  ASSERT_EQ(status, 0) << output;
  std::ifstream summary_file(prefix + ".json");
  const nlohmann::json summary = nlohmann::json::parse(summary_file);
  // plugin_gait_lower names 15 of its markers; the head, shoulder, elbow and wrist markers are placed
  // by their motion (docs/marker-sets.md), which leaves only the left hand without a marker.
  EXPECT_EQ(summary["marker_set"], "plugin_gait_lower+inferred");
  // Where the template fit and the rounds put them (1000 mm model): the coarse-to-fine template
  // search and its de-duplicated points give the set of the whole 3,060-placement grid (a template
  // centroid counting each place once moved these by up to 50 mm).
  const body::MarkerSet completed = app::load_marker_set(prefix + "_markerset.json");
  const std::vector<std::tuple<std::string, std::string, Eigen::Vector3d>> placed{
      {"Top.Head", "BUN", {2.64, 18.92, 152.59}},     {"Front.Head", "BUN", {-2.38, 76.53, 113.14}},
      {"R.Shoulder", "BT", {105.87, -11.02, 208.03}}, {"R.Wrist", "RW", {7.98, -19.93, -33.38}},
      {"L.Elbow", "LS", {-55.39, -22.45, -153.16}},   {"L.Wrist", "LE", {-3.71, 19.89, -155.31}}};
  for (const auto& [label, frame, offset] : placed) {
    const std::string& wanted = label;  // a lambda may not capture a structured binding before C++20
    const auto entry = std::find_if(completed.entries.begin(), completed.entries.end(),
                                    [&](const body::MarkerSetEntry& e) { return e.label == wanted; });
    ASSERT_NE(entry, completed.entries.end()) << label;
    EXPECT_EQ(entry->frame, frame) << label;
    EXPECT_LT((entry->offset - offset).norm(), 0.1) << label << ": " << entry->offset.transpose();
  }
  EXPECT_EQ(summary["unobserved"]["segments"], (std::vector<std::string>{"LW"}));
  EXPECT_EQ(summary["segments"].size(), 17u);
  const io::MotionTable motion = io::load_motion_csv(prefix + ".csv");
  const int lwx =
      6 + static_cast<int>(std::find(motion.joint_names.begin(), motion.joint_names.end(), "LWx") -
                           motion.joint_names.begin());
  const int lkx =
      6 + static_cast<int>(std::find(motion.joint_names.begin(), motion.joint_names.end(), "LKx") -
                           motion.joint_names.begin());
  long tracked = 0;
  for (Eigen::Index r = 0; r < motion.frames(); ++r) {
    EXPECT_TRUE(std::isnan(motion.values(r, lwx))) << r;
    tracked += std::isfinite(motion.values(r, lkx));
  }
  EXPECT_EQ(tracked, motion.frames());
  std::ifstream segments(prefix + "_segments.csv");
  std::string header;
  std::getline(segments, header);
  EXPECT_EQ(header.rfind("frame,time,root_sd_deg,BP_sd_deg,", 0), 0u) << header;
  // .mot cannot hold NaN: it has every frame, with the unobserved angles at 0.
  std::ifstream mot(prefix + ".mot");
  std::stringstream text;
  text << mot.rdbuf();
  EXPECT_EQ(text.str().find("nan"), std::string::npos);
}

}  // namespace
