// Faults real recordings have (issue 16), injected into the bundled simulated handstand and run
// through the program itself: Latin-1 text, a --truth file with wrong columns, an interrupt in the
// middle of a run, a recording in metres labelled mm, implausible frame rates and command-line
// errors. Each must end in one clear sentence and a non-zero status with no output written, or
// (Latin-1 text) in a complete run with valid UTF-8 everywhere; never a partial set of files.
#include "../cli_runner.hpp"
#include "motion_test_support.hpp"

#include <s2kf/body/label_text.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/c3d_writer.hpp>

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>
#include "address_sanitizer.hpp"

namespace s2kf {
namespace {

namespace fs = std::filesystem;
using test_support::read_text_file;
using test_support::run_command;
using test_support::scratch_directory;

const std::string kHandstand = std::string(S2KF_DATA_DIR) + "/handstand.c3d";
const std::string kFastOptions = " --no-calibrate --samples 93 --quiet";

/// The handstand's stored labels, in file order.
std::vector<std::string> stored_labels_of(const c3d::Recording& recording) {
  std::vector<std::string> labels;
  for (const c3d::PointLabel& label : recording.info.labels) labels.push_back(c3d::stored_label(label));
  return labels;
}

/// Every file (any depth) in `dir`, temporary ones included.
std::set<std::string> files_in(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file()) names.insert(entry.path().filename().string());
  return names;
}

/// A user error as the README promises it: status 1 and one line "s2kf: ..." that says `fragment`.
void expect_one_sentence(const test_support::CommandResult& r, const std::string& fragment) {
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output.rfind("s2kf: ", 0), 0u) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_NE(r.output.find(fragment), std::string::npos) << r.output;
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

/// `bytes` with every float32 `from` before `end` replaced by `to`, from byte `begin` on.
std::string replace_float(std::string bytes, float from, float to, std::size_t begin, std::size_t end) {
  char pattern[4], replacement[4];
  std::memcpy(pattern, &from, 4);
  std::memcpy(replacement, &to, 4);
  int replaced = 0;
  for (std::size_t at = begin; at + 4 <= std::min(end, bytes.size()); ++at)
    if (std::memcmp(&bytes[at], pattern, 4) == 0) std::memcpy(&bytes[at], replacement, 4), ++replaced;
  EXPECT_GT(replaced, 0);
  return bytes;
}

TEST(Faults, Latin1LabelsAreDecodedMatchedAndWrittenAsUtf8) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const std::string dir = scratch_directory("faults_latin1");
  c3d::Recording recording = c3d::read_c3d(kHandstand);
  std::vector<std::string> labels = stored_labels_of(recording);
  const auto c7 = std::find(labels.begin(), labels.end(), "C7");
  ASSERT_NE(c7, labels.end());
  *c7 = "C7\xC9";  // Latin-1 É, as a French lab's software stores it
  const std::string file = dir + "/latin1.c3d";
  c3d::write_c3d(file, labels, recording.info.rate, recording.positions, recording.visible);
  const std::string utf8_label = "C7\xC3\x89";

  // The reader hands on UTF-8 (the label as the file has it, each byte a Latin-1 character).
  const c3d::Recording read = c3d::read_c3d(file);
  EXPECT_EQ(read.info.labels[static_cast<std::size_t>(c7 - labels.begin())].name, utf8_label);

  const test_support::CommandResult json = run_command("c3d " + file + " --json");
  EXPECT_EQ(json.status, 0) << json.output;
  EXPECT_TRUE(is_utf8(json.output));
  EXPECT_NE(json.output.find("\"" + utf8_label + "\""), std::string::npos);

  // Tracked with the bundled set, the label matches nothing and is listed as ignored, in UTF-8.
  const test_support::CommandResult plain =
      run_command("track " + file + kFastOptions + " --out " + dir + "/plain");
  ASSERT_EQ(plain.status, 0) << plain.output;
  const std::string summary = read_text_file(dir + "/plain.json");
  EXPECT_TRUE(is_utf8(summary));
  EXPECT_NE(summary.find("\"" + utf8_label + "\""), std::string::npos) << summary;
  for (const char* name : {"plain.csv", "plain.mot", "plain.bvh", "plain.trc", "plain_markers.csv"})
    EXPECT_TRUE(fs::exists(dir + "/" + std::string(name))) << name;

  // A marker set that spells the label the same way matches it: no label is ignored.
  std::string set = read_text_file(std::string(S2KF_DATA_DIR) + "/markersets/kit.json");
  const std::string entry = "{\"label\": \"C7\", ";
  ASSERT_NE(set.find(entry), std::string::npos);
  set.replace(set.find(entry), entry.size(), entry + "\"aliases\": [\"C7\\u00C9\"], ");
  write_bytes(dir + "/french.json", set);
  const test_support::CommandResult matched = run_command("track " + file + kFastOptions + " --markerset " +
                                                          dir + "/french.json --out " + dir + "/matched");
  ASSERT_EQ(matched.status, 0) << matched.output;
  const std::string matched_summary = read_text_file(dir + "/matched.json");
  EXPECT_NE(matched_summary.find("\"labels_ignored\": []"), std::string::npos) << matched_summary;
}

TEST(Faults, TruthWithWrongColumnsIsRefusedBeforeTrackingAndNothingIsWritten) {
  const std::string dir = scratch_directory("faults_truth");
  std::string truth = read_text_file(std::string(S2KF_DATA_DIR) + "/handstand_truth.csv");
  truth.replace(truth.find(",BPx,"), 5, ",NotAJoint,");  // right rows, one wrong column
  write_bytes(dir + "/wrong_truth.csv", truth);
  write_bytes(dir + "/run.csv", "an earlier run\n");  // an earlier output stays as it was
  const auto start = std::chrono::steady_clock::now();
  const test_support::CommandResult r = run_command("track " + kHandstand + kFastOptions + " --truth " + dir +
                                                    "/wrong_truth.csv --out " + dir + "/run");
  expect_one_sentence(r, "joint columns");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 30.0);
  EXPECT_EQ(files_in(dir), (std::set<std::string>{"wrong_truth.csv", "run.csv"}));
  EXPECT_EQ(read_text_file(dir + "/run.csv"), "an earlier run\n");
}

/// Starts `s2kf args...` in the background with its output discarded.
pid_t start_program(const std::vector<std::string>& args) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv{const_cast<char*>(S2KF_CLI)};
    for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
    argv.push_back(nullptr);
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, STDOUT_FILENO);
    dup2(null, STDERR_FILENO);
    execv(S2KF_CLI, argv.data());
    _exit(127);
  }
  return pid;
}

class Interrupt : public ::testing::TestWithParam<int> {};

TEST_P(Interrupt, InTheMiddleOfARunRemovesEveryTemporaryFileAndExitsNonZero) {
  const int signal_number = GetParam();
  const std::string dir = scratch_directory("faults_interrupt_" + std::to_string(signal_number));
  write_bytes(dir + "/run.json", "{}\n");  // an earlier run's summary stays as it was
  // --realtime paces the 675 frames at 100 Hz: the run takes about 7 s, outputs open throughout.
  const pid_t pid = start_program({"track", kHandstand, "--no-calibrate", "--samples", "93", "--quiet",
                                   "--realtime", "--out", dir + "/run"});
  ASSERT_GT(pid, 0);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!fs::exists(dir + "/run.csv.tmp") && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_TRUE(fs::exists(dir + "/run.csv.tmp")) << "the run never opened its outputs";
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // some rows written
  ASSERT_EQ(kill(pid, signal_number), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by the signal itself, without cleaning up";
  EXPECT_EQ(WEXITSTATUS(status), 128 + signal_number);
  EXPECT_EQ(files_in(dir), std::set<std::string>{"run.json"});
  EXPECT_EQ(read_text_file(dir + "/run.json"), "{}\n");
}

INSTANTIATE_TEST_SUITE_P(Signals, Interrupt, ::testing::Values(SIGINT, SIGTERM),
                         [](const auto& info) { return info.param == SIGINT ? "SIGINT" : "SIGTERM"; });

TEST(Faults, MetresLabelledMillimetresAreRefusedWithOrWithoutHeight) {
  const std::string dir = scratch_directory("faults_metres");
  c3d::Recording recording = c3d::read_c3d(kHandstand);
  const std::string file = dir + "/metres.c3d";
  c3d::write_c3d(file, stored_labels_of(recording), recording.info.rate, recording.positions / 1000.0,
                 recording.visible);  // POINT:UNITS says mm
  for (const std::string& height : {std::string(), std::string(" --height 1750")}) {
    SCOPED_TRACE(height);
    const test_support::CommandResult r =
        run_command("track " + file + kFastOptions + height + " --out " + dir + "/run");
    expect_one_sentence(r, "in metres, not millimetres");
    EXPECT_EQ(files_in(dir), std::set<std::string>{"metres.c3d"});
  }
}

TEST(Faults, ImplausibleFrameRatesAreWarnedAboutAndRefused) {
  const std::string dir = scratch_directory("faults_rate");
  c3d::Recording recording = c3d::read_c3d(kHandstand);
  const Eigen::MatrixXd positions = recording.positions.leftCols(60);
  const Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic> visible = recording.visible.leftCols(60);
  // Rates a corrupt header gives, written as they are (the writer takes any positive rate).
  for (const double rate : {1e-40, 1e30, 0.5, 250000.0}) {
    SCOPED_TRACE(rate);
    const std::string file = dir + "/rate.c3d";
    c3d::write_c3d(file, stored_labels_of(recording), rate, positions, visible);
    const test_support::CommandResult shown = run_command("c3d " + file);
    EXPECT_EQ(shown.status, 0) << shown.output;
    EXPECT_NE(shown.output.find("warning: the frame rate"), std::string::npos) << shown.output;
    EXPECT_NE(shown.output.find("is implausible"), std::string::npos) << shown.output;
    expect_one_sentence(run_command("track " + file + kFastOptions + " --out " + dir + "/run"),
                        "is not one motion capture runs at");
    EXPECT_EQ(files_in(dir), std::set<std::string>{"rate.c3d"});
  }
  // 0, NaN and negative rates: patched into the header and the RATE parameters of a 123.25 Hz file.
  const std::string file = dir + "/rate.c3d";
  c3d::write_c3d(file, stored_labels_of(recording), 123.25, positions, visible);
  const std::string bytes = read_text_file(file);
  const std::size_t data_start =
      static_cast<std::size_t>(c3d::C3dReader(file).info().data_offset);  // the parameters end here
  for (const float bad : {0.0f, std::numeric_limits<float>::quiet_NaN(), -100.0f}) {
    SCOPED_TRACE(bad);
    write_bytes(file, replace_float(bytes, 123.25f, bad, 0, data_start));
    const test_support::CommandResult shown = run_command("c3d " + file);
    EXPECT_EQ(shown.status, 0) << shown.output;
    EXPECT_NE(shown.output.find("warning: no valid frame rate"), std::string::npos) << shown.output;
    expect_one_sentence(run_command("track " + file + kFastOptions + " --out " + dir + "/run"),
                        "no valid frame rate");
    // Only the parameters wrong: the header's rate is used, and said.
    write_bytes(file, replace_float(bytes, 123.25f, bad, 512, data_start));
    const test_support::CommandResult parameter_only = run_command("c3d " + file);
    EXPECT_NE(parameter_only.output.find("the header's 123.25 Hz is used"), std::string::npos)
        << parameter_only.output;
  }
}

TEST(Faults, CommandLineErrorsExitWithStatusOneAndOneSentence) {
  expect_one_sentence(run_command("no-such-command"),
                      "there is no command no-such-command (the commands are c3d, calibrate,");
  for (const std::string& arguments :
       {std::string(""), std::string("track"), std::string("c3d"), "track " + kHandstand + " --height 10",
        "track " + kHandstand + " --samples many", "track " + kHandstand + " --no-such-option",
        "track " + kHandstand + " --method kalman", "c3d " + kHandstand + " --frames"}) {
    SCOPED_TRACE(arguments);
    expect_one_sentence(run_command(arguments), "--help).");
  }
  const test_support::CommandResult help = run_command("track --help");
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.output.find("--truth"), std::string::npos);
  EXPECT_EQ(run_command("--version").status, 0);
}

}  // namespace
}  // namespace s2kf
