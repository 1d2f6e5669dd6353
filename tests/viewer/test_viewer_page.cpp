// The viewer page (`s2kf track --html`, `s2kf view`): rendered by headless chromium, the skeleton it
// draws is where the library's forward kinematics puts it, the timeline moves it, damaged data
// blocks are reported on the page, long motions are decimated, and bad input to `s2kf view` fails
// cleanly. The live page (`s2kf live --view`) follows a stream `s2kf serve` sends. Tests that need chromium
// skip, saying why, where it cannot run.
#include "child_process.hpp"
#include "cli_runner.hpp"
#include "viewer/headless_chromium.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/io/motion_files.hpp>

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>
#include "test_files.hpp"

#ifdef S2KF_CLI

namespace {

namespace fs = std::filesystem;
using s2kf::test_support::run_command;

// ctest runs every test in its own process, in parallel: each process works in its own directory,
// and reads the recording and its tracked pages from a shared one (ViewerPage::SetUpTestSuite).
const fs::path kWork = fs::path(s2kf::test_support::tmp_dir()) / ("viewer_" + std::to_string(::getpid()));
const fs::path kShared = fs::path(s2kf::test_support::tmp_dir()) / "viewer_shared";
constexpr double kHeightMm = 1750;
constexpr int kFrames = 150;

/// The skeleton points the page draws, in its order: the root, then every joint that starts a
/// group (the frames with their own centre). Written out here rather than taken from the page.
std::vector<int> skeleton_frames(const s2kf::body::BodyModel& model) {
  std::vector<int> frames{0};
  for (int j = 0; j < model.joint_count(); ++j)
    if (!model.joints[static_cast<std::size_t>(j)].translation.isZero(0)) frames.push_back(j + 1);
  return frames;
}

std::string page_text(const fs::path& path) { return s2kf::test_support::slurp(path); }

/// The JSON the page writes into <pre id="scene-state">, from chromium's DOM dump.
nlohmann::json scene_state(const std::string& dom) {
  const std::string open = "<pre id=\"scene-state\" hidden=\"\">";
  const std::size_t begin = dom.find(open);
  if (begin == std::string::npos) return nullptr;
  const std::size_t end = dom.find("</pre>", begin);
  std::string text = dom.substr(begin + open.size(), end - begin - open.size());
  const std::pair<const char*, const char*> entities[] = {
      {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&amp;", "&"}};
  for (const auto& [entity, character] : entities)
    for (std::size_t at = 0; (at = text.find(entity, at)) != std::string::npos; ++at)
      text.replace(at, std::string(entity).size(), character);
  return nlohmann::json::parse(text, nullptr, false);
}

/// Shared by all tests: one simulated recording tracked twice, once with the subject as given
/// (so the test can rebuild the model: the kit set is the body model's own markers) and once with
/// the default calibration (for `s2kf view`, which must rebuild the calibrated subject itself).
/// They are written once per ctest run, by the test viewer_page_files (a fixture every test of the
/// page requires; S2KF_VIEWER_WRITE_FILES set), and read by each test's process; a process that
/// finds none, or finds files of another build of the program, writes them itself.
class ViewerPage : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::remove_all(kWork);
    fs::create_directories(kWork);
    recording_ = (kShared / "handstand.c3d").string();
    truth_ = (kShared / "handstand_truth.csv").string();
    plain_ = (kShared / "plain").string();
    calibrated_ = (kShared / "calibrated").string();
    // The program's modification time names the build that wrote the files.
    const std::string build = std::to_string(fs::last_write_time(S2KF_CLI).time_since_epoch().count());
    const fs::path complete = kShared / "complete", unavailable = kShared / "chromium_unavailable.txt";
    if (std::getenv("S2KF_VIEWER_WRITE_FILES") != nullptr || !fs::exists(complete) ||
        s2kf::test_support::slurp(complete) != build) {
      write_shared_files();
      if (HasFatalFailure()) return;
      std::ofstream(unavailable) << s2kf::test_support::chromium_unavailable_reason(kWork);
      std::ofstream(complete) << build;
    }
    unavailable_ = s2kf::test_support::slurp(unavailable);
  }

  static void write_shared_files() {
    fs::remove_all(kShared);
    fs::create_directories(kShared);
    const auto simulate = run_command("simulate --motion handstand --frames " + std::to_string(kFrames) +
                                      " --height " + std::to_string(kHeightMm) + " --out " + recording_);
    ASSERT_EQ(simulate.status, 0) << simulate.output;
    const auto plain =
        run_command("track " + recording_ + " --out " + plain_ + " --markerset kit --no-calibrate" +
                    " --height " + std::to_string(kHeightMm) + " --truth " + truth_ + " --html --quiet");
    ASSERT_EQ(plain.status, 0) << plain.output;
    // A calibration pass with a sample count of its own, which `s2kf view` must read back.
    const auto calibrated = run_command("track " + recording_ + " --out " + calibrated_ +
                                        " --calibration-samples 93 --html --quiet");
    ASSERT_EQ(calibrated.status, 0) << calibrated.output;
  }

  static void TearDownTestSuite() { fs::remove_all(kWork); }

  void SetUp() override { ASSERT_TRUE(fs::exists(plain_ + ".html")) << "the fixture's track --html failed"; }

  /// The page's scene state after opening `page` with `fragment`; fails the test on console errors.
  static nlohmann::json open_page(const std::string& page, const std::string& fragment) {
    const auto run = s2kf::test_support::run_chromium("file://" + fs::absolute(page).string() + fragment,
                                                      "--dump-dom", kWork);
    EXPECT_EQ(run.stderr_text.find("Uncaught"), std::string::npos) << run.stderr_text;
    const nlohmann::json state = scene_state(run.stdout_text);
    EXPECT_TRUE(state.is_object()) << "no scene state in the page; chromium said:\n"
                                   << run.stderr_text.substr(0, 2000);
    return state.is_object() ? state : nlohmann::json::object();
  }

  /// Joint centres (mm) of a row of a motion CSV, posed on `model` by the library.
  static std::vector<Eigen::Vector3d> fk_joints(const s2kf::body::BodyModel& model,
                                                const s2kf::io::MotionTable& motion, long frame) {
    const auto row = motion.values.row(frame);
    s2kf::body::Pose pose;
    pose.root_position = row.segment<3>(0).transpose();
    pose.root_rpy = row.segment<3>(3).transpose();
    pose.joints = row.tail(row.size() - 6).transpose();
    const s2kf::body::FrameTransforms frames = s2kf::body::joint_frames(model, pose);
    std::vector<Eigen::Vector3d> joints;
    for (const int f : skeleton_frames(model)) joints.push_back(frames.origins[static_cast<std::size_t>(f)]);
    return joints;
  }

  /// Largest distance (mm) between the page's joint centres and `expected`.
  static double largest_joint_error(const nlohmann::json& state,
                                    const std::vector<Eigen::Vector3d>& expected) {
    EXPECT_EQ(state["joints"].size(), expected.size());
    double worst = 0;
    for (std::size_t p = 0; p < std::min(expected.size(), state["joints"].size()); ++p) {
      const auto& mm = state["joints"][p]["mm"];
      worst = std::max(worst, (Eigen::Vector3d(mm[0], mm[1], mm[2]) - expected[p]).norm());
    }
    return worst;
  }

  static std::string recording_, truth_, plain_, calibrated_, unavailable_;
};
std::string ViewerPage::recording_, ViewerPage::truth_, ViewerPage::plain_, ViewerPage::calibrated_,
    ViewerPage::unavailable_;

#define SKIP_WITHOUT_CHROMIUM() \
  if (!unavailable_.empty()) GTEST_SKIP() << "chromium cannot run: " << unavailable_

// The files every other test reads (the test viewer_page_files writes them for a ctest run).
TEST_F(ViewerPage, TheRecordingIsTrackedIntoTwoPages) {
  for (const std::string& prefix : {plain_, calibrated_})
    for (const char* suffix : {".csv", ".json", ".html"})
      EXPECT_TRUE(fs::exists(prefix + suffix)) << prefix + suffix;
  EXPECT_EQ(s2kf::io::load_motion_csv(plain_ + ".csv").frame.size(), static_cast<std::size_t>(kFrames));
  EXPECT_NE(page_text(calibrated_ + ".json").find("\"calibration\": {"), std::string::npos)
      << "the second run was meant to be calibrated";
}

TEST_F(ViewerPage, SkeletonIsDrawnWhereForwardKinematicsPutsIt) {
  SKIP_WITHOUT_CHROMIUM();
  const long frame = 100;
  // Only the skeleton: the markers and the truth would cover joint pixels.
  const nlohmann::json state = open_page(plain_ + ".html", "#frame=" + std::to_string(frame) + "&layers=");
  ASSERT_TRUE(state.value("ok", false)) << state.dump();
  EXPECT_TRUE(state["errors"].empty()) << state["errors"].dump();
  EXPECT_EQ(state["frame"], frame);

  const s2kf::body::BodyModel model = s2kf::body::mmm_body_model(kHeightMm);
  const s2kf::io::MotionTable motion = s2kf::io::load_motion_csv(plain_ + ".csv");
  const auto expected = fk_joints(model, motion, frame);
  // float32 storage of coordinates around 1-2 m: about 1e-4 mm.
  const double error = largest_joint_error(state, expected);
  EXPECT_LT(error, 0.01) << "page vs forward kinematics, mm";
  RecordProperty("joint_position_error_mm", std::to_string(error));
  // The check can fail: another frame's pose is centimetres away.
  EXPECT_GT(largest_joint_error(state, fk_joints(model, motion, 10)), 50.0);

  // Pixels: the library's joint centres through the page's camera land on the page's pixels, and
  // the canvas shows the joint colour there (the skeleton really is drawn at those pixels).
  const auto& m = state["view_projection"];
  Eigen::Matrix4d view_projection;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) view_projection(r, c) = m[static_cast<std::size_t>(4 * c + r)];
  const double width = state["canvas"][0], height = state["canvas"][1];
  double worst_pixel = 0;
  int drawn = 0;
  for (std::size_t p = 0; p < expected.size(); ++p) {
    const Eigen::Vector4d clip = view_projection * (Eigen::Vector4d() << expected[p] * 0.001, 1).finished();
    const double x = (clip.x() / clip.w() + 1) / 2 * width, y = (1 - clip.y() / clip.w()) / 2 * height;
    const auto& joint = state["joints"][p];
    worst_pixel = std::max(
        worst_pixel, std::hypot(x - joint["pixel"][0].get<double>(), y - joint["pixel"][1].get<double>()));
    ASSERT_TRUE(x > 0 && x < width && y > 0 && y < height) << "joint " << p << " is off the canvas";
    const auto& rgb = joint["rgb"];
    const bool joint_colour = std::abs(rgb[0].get<int>() - 0xf2) <= 2 &&
                              std::abs(rgb[1].get<int>() - 0xf2) <= 2 &&
                              std::abs(rgb[2].get<int>() - 0xf2) <= 2;
    EXPECT_TRUE(joint_colour) << joint["name"] << " at pixel (" << x << ", " << y << ") shows " << rgb.dump();
    drawn += joint_colour;
  }
  EXPECT_LT(worst_pixel, 0.5);
  RecordProperty("joint_pixel_error_px", std::to_string(worst_pixel));
  std::cout << "page vs C++ forward kinematics at frame " << frame << ": " << error << " mm, " << worst_pixel
            << " px; joint colour at " << drawn << " of " << expected.size() << " joint pixels\n";

  // The screenshot of the same view, kept beside the test's files for a person to look at.
  const fs::path screenshot = kWork / "frame100.png";
  fs::remove(screenshot);
  s2kf::test_support::run_chromium("file://" + fs::absolute(plain_ + ".html").string() + "#frame=100",
                                   "--screenshot=" + screenshot.string(), kWork);
  ASSERT_TRUE(fs::exists(screenshot));
  EXPECT_GT(fs::file_size(screenshot), 20000u) << "a blank screenshot";
  fs::copy_file(screenshot, fs::path(s2kf::test_support::tmp_dir()) / "viewer_frame100.png",
                fs::copy_options::overwrite_existing);
}

TEST_F(ViewerPage, TimelineMovesTheSkeleton) {
  SKIP_WITHOUT_CHROMIUM();
  const nlohmann::json state = open_page(plain_ + ".html", "#frame=10&scrub=120");
  ASSERT_TRUE(state.value("ok", false)) << state.dump();
  EXPECT_TRUE(state["errors"].empty()) << state["errors"].dump();
  EXPECT_EQ(state["opened"]["frame"], 10);
  EXPECT_EQ(state["frame"], 120);
  const s2kf::body::BodyModel model = s2kf::body::mmm_body_model(kHeightMm);
  const s2kf::io::MotionTable motion = s2kf::io::load_motion_csv(plain_ + ".csv");
  EXPECT_LT(largest_joint_error(state["opened"], fk_joints(model, motion, 10)), 0.01);
  EXPECT_LT(largest_joint_error(state, fk_joints(model, motion, 120)), 0.01);
  EXPECT_GT(largest_joint_error(state, fk_joints(model, motion, 10)), 50.0) << "the pose did not change";
}

TEST_F(ViewerPage, TruthIsShownAndTheDataLayoutIsAsDocumented) {
  const std::string page = page_text(plain_ + ".html");
  const std::size_t begin = page.find("<script type=\"application/json\" id=\"s2kf-meta\">");
  ASSERT_NE(begin, std::string::npos);
  const std::size_t start = page.find('>', begin) + 1;
  const nlohmann::json meta =
      nlohmann::json::parse(page.substr(start, page.find("</script>", start) - start));
  // docs/viewer.md: frame, time, pose (46), mean distance, 17 joint centres, 50 model markers, 50
  // recorded markers and, with --truth, 17 true joint centres: 451 floats, 1804 bytes per frame.
  EXPECT_EQ(meta["floats_per_frame"], 1 + 1 + 46 + 1 + 3 * 17 + 3 * 50 + 3 * 50 + 3 * 17);
  EXPECT_EQ(meta["frames_stored"], kFrames);
  EXPECT_EQ(meta["decimated"], false);
  EXPECT_EQ(meta["blocks"].back()["name"], "truth_skeleton");
  EXPECT_EQ(meta["summary"]["marker_set"], "kit");
  // Nothing is fetched: no http(s) or protocol-relative URL in the page apart from licence text.
  EXPECT_EQ(page.find("src=\"http"), std::string::npos);
  EXPECT_EQ(page.find("\"https://"), std::string::npos);
}

TEST_F(ViewerPage, ViewRebuildsTheTrackedModelOfACalibratedRun) {
  // `s2kf view` rebuilds the calibrated subject from the summary and the recording; its page must
  // hold exactly the data of the page `track --html` wrote with the model in memory.
  const std::string tracked = page_text(calibrated_ + ".html");
  // In this test's own folder: the shared page stays as track wrote it for the other tests.
  const std::string prefix = (kWork / "calibrated").string();
  for (const char* suffix : {".csv", ".json"})
    fs::copy_file(calibrated_ + suffix, prefix + suffix, fs::copy_options::overwrite_existing);
  const auto view = run_command("view " + prefix);
  ASSERT_EQ(view.status, 0) << view.output;
  const std::string viewed = page_text(prefix + ".html");
  const auto data = [](const std::string& page) {
    const std::size_t begin = page.find("id=\"s2kf-data\">");
    return page.substr(begin, page.find("</script>", begin) - begin);
  };
  ASSERT_GT(data(tracked).size(), 1000u);
  EXPECT_TRUE(data(tracked) == data(viewed)) << "s2kf view drew another model than s2kf track";
  EXPECT_NE(page_text(calibrated_ + ".json").find("\"calibration\": {"), std::string::npos)
      << "the run was meant to be calibrated";
}

TEST_F(ViewerPage, LongMotionsAreDecimatedAndThePageSaysSo) {
  SKIP_WITHOUT_CHROMIUM();
  const std::string prefix = (kWork / "decimated").string();
  for (const char* suffix : {".csv", ".json"})
    fs::copy_file(plain_ + suffix, prefix + suffix, fs::copy_options::overwrite_existing);
  // 0.1 MiB holds 58 of the 150 records of 1804 bytes: every 3rd frame.
  const auto view = run_command("view " + prefix + " --truth " + truth_ + " --max-data-mb 0.1");
  ASSERT_EQ(view.status, 0) << view.output;
  const nlohmann::json state = open_page(prefix + ".html", "#frame=31");
  ASSERT_TRUE(state.value("ok", false)) << state.dump();
  EXPECT_TRUE(state["decimated"].get<bool>());
  EXPECT_EQ(state["frames_stored"], 50);
  EXPECT_EQ(state["frame"], 30) << "the nearest stored frame";
  const auto run = s2kf::test_support::run_chromium("file://" + fs::absolute(prefix + ".html").string(),
                                                    "--dump-dom", kWork);
  EXPECT_NE(run.stdout_text.find("1 frame in 3 is shown (50 of 150 frames)"), std::string::npos);
}

TEST_F(ViewerPage, DamagedDataBlocksAreNamedOnThePage) {
  SKIP_WITHOUT_CHROMIUM();
  const std::string good = page_text(plain_ + ".html");
  const std::string marker = "id=\"s2kf-data\">";
  const std::size_t data = good.find(marker) + marker.size();
  struct Damage {
    std::string name, page, message;
  };
  std::string flipped = good;
  flipped[data + 1000] = flipped[data + 1000] == 'A' ? 'B' : 'A';  // same length, another byte
  std::string cut = good;
  cut.erase(data + 100, 4000);  // a truncated block
  const std::size_t open = good.rfind("<script", good.find(marker));
  const std::string missing = good.substr(0, open) + good.substr(good.find("</script>", open) + 9);
  std::string not_base64 = good;
  not_base64[data + 10] = '!';
  const std::vector<Damage> damages = {
      {"flipped", flipped, "checksum does not match"},
      {"cut", cut, "bytes, the metadata promises"},
      {"missing", missing, "no motion data block"},
      {"not_base64", not_base64, "not valid base64"},
  };
  for (const Damage& damage : damages) {
    const fs::path page = kWork / ("damaged_" + damage.name + ".html");
    std::ofstream(page, std::ios::binary) << damage.page;
    const auto run =
        s2kf::test_support::run_chromium("file://" + fs::absolute(page).string(), "--dump-dom", kWork);
    const nlohmann::json state = scene_state(run.stdout_text);
    ASSERT_TRUE(state.is_object()) << damage.name;
    EXPECT_FALSE(state["ok"].get<bool>()) << damage.name;
    EXPECT_NE(state["error"].get<std::string>().find(damage.message), std::string::npos)
        << damage.name << ": " << state["error"];
    // Shown to the person, not only in the hidden state.
    EXPECT_NE(run.stdout_text.find("<div id=\"error\">"), std::string::npos) << damage.name;
  }
}

TEST_F(ViewerPage, LivePageFollowsTheStream) {
  SKIP_WITHOUT_CHROMIUM();
  const fs::path dir = kWork / "live";
  fs::create_directories(dir);
  s2kf::test_support::ServeProcess server(recording_, dir, {"--loop"});
  const std::string prefix = (dir / "live").string();
  s2kf::test_support::ChildProcess live({S2KF_CLI, "live", server.address(), "--markerset", "kit",
                                         "--no-calibrate", "--height", std::to_string(kHeightMm), "--seconds",
                                         "60", "--view", "0", "--formats", "csv", "--quiet", "--out", prefix},
                                        dir / "live_output.txt");
  std::string url;
  const bool printed = live.wait_for_output(
      [&](const std::string& out) {
        const std::size_t at = out.find("http://"), end = out.find('\n', at);
        if (at == std::string::npos || end == std::string::npos) return false;
        url = out.substr(at, end - at);
        return true;
      },
      20);
  ASSERT_TRUE(printed) << live.output();
  // The page's test hook: its state at the 20th frame received and at the 60th.
  const auto run = s2kf::test_support::run_chromium(url + "#reads=20,60&layers=", "--dump-dom", kWork);
  EXPECT_EQ(live.stop(SIGINT), 0) << live.output();
  EXPECT_EQ(run.stderr_text.find("Uncaught"), std::string::npos) << run.stderr_text;
  const nlohmann::json state = scene_state(run.stdout_text);
  ASSERT_TRUE(state.is_object()) << "no scene state; chromium said:\n" << run.stderr_text.substr(0, 2000);
  ASSERT_TRUE(state.value("ok", false)) << state.dump();
  EXPECT_TRUE(state["errors"].empty()) << state["errors"].dump();
  EXPECT_EQ(state["frames_received"], 60);
  ASSERT_TRUE(state["opened"].is_object()) << state.dump();

  // Both drawn poses are forward kinematics of the poses s2kf live tracked (its CSV), and differ.
  const s2kf::body::BodyModel model = s2kf::body::mmm_body_model(kHeightMm);
  const s2kf::io::MotionTable motion = s2kf::io::load_motion_csv(prefix + ".csv");
  const auto row_of = [&](long frame) {
    const auto found = std::find(motion.frame.begin(), motion.frame.end(), frame);
    EXPECT_NE(found, motion.frame.end()) << "frame " << frame << " is not in the CSV";
    return found == motion.frame.end() ? 0L : static_cast<long>(found - motion.frame.begin());
  };
  const long first = state["opened"]["frame"].get<long>(), second = state["frame"].get<long>();
  EXPECT_LT(first, second);
  EXPECT_LT(largest_joint_error(state["opened"], fk_joints(model, motion, row_of(first))), 0.01);
  EXPECT_LT(largest_joint_error(state, fk_joints(model, motion, row_of(second))), 0.01);
  const double moved = largest_joint_error(state, fk_joints(model, motion, row_of(first)));
  EXPECT_GT(moved, 5.0) << "the skeleton did not move between the two reads";
  std::cout << "live page: frames " << first << " and " << second << ", the skeleton moved " << moved
            << " mm (largest joint)\n";
  const nlohmann::json summary = nlohmann::json::parse(s2kf::test_support::slurp(prefix + ".json"));
  EXPECT_EQ(summary["live"]["view"]["browsers"], 1);
  EXPECT_GE(summary["live"]["view"]["frames_sent"].get<long>(), 60);
}

TEST_F(ViewerPage, ViewOfABadPrefixSaysWhyAndWritesNothing) {
  const fs::path dir = kWork / "bad";
  fs::create_directories(dir);
  const std::string missing = (dir / "nothing").string();
  auto result = run_command("view " + missing);
  EXPECT_EQ(result.status, 1);
  EXPECT_NE(result.output.find("nothing.json: no such file"), std::string::npos) << result.output;
  EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 1) << result.output;

  const std::string broken_json = (dir / "broken_json").string();
  std::ofstream(broken_json + ".json") << "{\"input\": ";
  fs::copy_file(plain_ + ".csv", broken_json + ".csv", fs::copy_options::overwrite_existing);
  result = run_command("view " + broken_json);
  EXPECT_EQ(result.status, 1);
  EXPECT_NE(result.output.find("not valid JSON"), std::string::npos) << result.output;

  const std::string broken_csv = (dir / "broken_csv").string();
  fs::copy_file(plain_ + ".json", broken_csv + ".json", fs::copy_options::overwrite_existing);
  std::string csv = page_text(plain_ + ".csv");
  csv.replace(csv.find('\n', csv.size() / 2) + 1, 3, "x,y");
  std::ofstream(broken_csv + ".csv") << csv;
  result = run_command("view " + broken_csv);
  EXPECT_EQ(result.status, 1);
  EXPECT_NE(result.output.find("is not a number"), std::string::npos) << result.output;
  EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 1) << result.output;

  const std::string short_csv = (dir / "short_csv").string();
  fs::copy_file(plain_ + ".json", short_csv + ".json", fs::copy_options::overwrite_existing);
  std::ofstream(short_csv + ".csv") << csv.substr(0, csv.find('\n') + 1);
  result = run_command("view " + short_csv);
  EXPECT_EQ(result.status, 1);
  EXPECT_NE(result.output.find("no rows"), std::string::npos) << result.output;

  // No page and no temporary file for any of them.
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".html"), std::string::npos) << entry.path();
}

}  // namespace

#endif  // S2KF_CLI
