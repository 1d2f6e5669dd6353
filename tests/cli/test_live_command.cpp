// `s2kf live` against `s2kf serve` over loopback: the same joint angles as `s2kf track` on the same
// file with the same subject, the faults of a stream, and a refused connection.
#include "address_sanitizer.hpp"
#include "child_process.hpp"
#include "cli_runner.hpp"
#include "test_files.hpp"

#include <nlohmann/json.hpp>

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;
using namespace s2kf::test_support;

using Server = ServeProcess;

/// A subject calibrated on walk.c3d (so that live and track run the same filter), made once per
/// test program, in the running test's own folder: ctest runs each test as a program of its own,
/// side by side, and two calibrations writing one file rename each other's temporary files away.
std::string walk_subject() {
  static const std::string subject = [] {
    const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    const fs::path path = scratch("live/" + test) / "walk_subject.json";
    const CommandResult r = run_command("calibrate " + data_file("walk.c3d") +
                                        " --frames 150 --iterations 1 --quiet --out " + path.string());
    EXPECT_EQ(r.status, 0) << r.output;
    return path.string();
  }();
  return subject;
}

/// A UDP socket on a free loopback port, for the poses `s2kf live --udp-json` sends.
struct UdpReceiver {
  int socket_fd = socket(AF_INET, SOCK_DGRAM, 0);
  int port = 0;
  UdpReceiver() {
    const int buffer = 1 << 20;
    setsockopt(socket_fd, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    if (socket_fd >= 0 && bind(socket_fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
        getsockname(socket_fd, reinterpret_cast<sockaddr*>(&address), &length) == 0)
      port = ntohs(address.sin_port);
  }
  ~UdpReceiver() { close(socket_fd); }
  UdpReceiver(const UdpReceiver&) = delete;
  UdpReceiver& operator=(const UdpReceiver&) = delete;
  /// The next datagram, waiting at most `timeout_ms` (0: only one already here); false if none came.
  bool receive(std::string& datagram, int timeout_ms) const {
    pollfd ready{socket_fd, POLLIN, 0};
    if (poll(&ready, 1, timeout_ms) <= 0) return false;
    char bytes[65536];
    const ssize_t n = recv(socket_fd, bytes, sizeof bytes, 0);
    if (n <= 0) return false;
    datagram.assign(bytes, static_cast<std::size_t>(n));
    return true;
  }
};

nlohmann::json summary_of(const std::string& prefix) {
  return nlohmann::json::parse(read_text(prefix + ".json"));
}

TEST(LiveCommand, SameJointAnglesAsTrackOnTheServedFile) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = empty_scratch("live_same");
  const std::string subject = walk_subject();
  const std::string tracked = (dir / "tracked").string();
  const CommandResult track = run_command("track " + data_file("walk.c3d") + " --subject " + subject +
                                          " --formats csv --quiet --out " + tracked);
  ASSERT_EQ(track.status, 0) << track.output;
  Server server(data_file("walk.c3d"), dir);
  const std::string live = (dir / "live").string();
  const CommandResult r = run_command("live " + server.address() + " --subject " + subject +
                                      " --frames 300 --backlog 100000 --formats csv --quiet --out " + live);
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json summary = summary_of(live);
  ASSERT_EQ(summary["live"]["frames_dropped_busy"], 0);
  ASSERT_EQ(summary["live"]["frames_missing"], 0);
  // The receiving thread may read a frame or two more before the stream is ended after the 300th.
  EXPECT_GE(summary["live"]["frames_received"].get<long>(), 300);
  // The frames after the first second; none waited behind the held second (the backlog is large).
  EXPECT_EQ(summary["live"]["latency_ms"]["frames"], 200);
  // Median and p99 from the fixed-memory histogram, the max exact: in order, and the misses counted.
  const nlohmann::json& latency = summary["live"]["latency_ms"];
  EXPECT_GT(latency["median"].get<double>(), 0);
  EXPECT_LE(latency["median"].get<double>(), latency["p99"].get<double>());
  EXPECT_LE(latency["p99"].get<double>(), latency["max"].get<double>());
  EXPECT_GE(latency["deadline_misses"].get<long>(), 0);
  EXPECT_EQ(summary["live"]["catch_up"]["frames"], 0);
  const auto expected = csv_rows(read_text(tracked + ".csv"));
  const auto got = csv_rows(read_text(live + ".csv"));
  ASSERT_EQ(got.size(), 301u);  // header and 300 frames
  ASSERT_EQ(got[0], expected[0]);
  double largest = 0;
  for (std::size_t row = 1; row < got.size(); ++row) {
    ASSERT_EQ(got[row].size(), expected[row].size());
    for (std::size_t c = 0; c < got[row].size(); ++c) {
      const double a = std::strtod(got[row][c].c_str(), nullptr),
                   b = std::strtod(expected[row][c].c_str(), nullptr);
      if (std::isnan(a) || std::isnan(b)) {
        EXPECT_EQ(std::isnan(a), std::isnan(b)) << "row " << row << " column " << got[0][c];
        continue;
      }
      largest = std::max(largest, std::abs(a - b));
    }
  }
  EXPECT_LT(largest, 1e-6);
}

TEST(LiveCommand, EveryPoseGoesOutAsAJsonLineOverUdp) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = empty_scratch("live_udp");
  const UdpReceiver receiver;
  ASSERT_GT(receiver.port, 0);
  Server server(data_file("walk.c3d"), dir);
  const std::string live = (dir / "live").string();
  const CommandResult r =
      run_command("live " + server.address() + " --subject " + walk_subject() +
                  " --frames 60 --backlog 100000 --formats csv --quiet --udp-json 127.0.0.1:" +
                  std::to_string(receiver.port) + " --out " + live);
  ASSERT_EQ(r.status, 0) << r.output;
  std::vector<nlohmann::json> messages;
  for (std::string datagram; receiver.receive(datagram, 0);) {
    ASSERT_EQ(datagram.back(), '\n');
    messages.push_back(nlohmann::json::parse(datagram));
  }
  ASSERT_EQ(messages.size(), 60u);
  const auto rows = csv_rows(read_text(live + ".csv"));
  for (std::size_t f = 0; f < messages.size(); ++f) {
    EXPECT_EQ(messages[f]["frame"], f);
    EXPECT_NEAR(messages[f]["time"].get<double>(), 0.01 * static_cast<double>(f), 1e-9);
    for (std::size_t c = 2; c < rows[0].size(); ++c) {
      const nlohmann::json& value = messages[f]["pose"][rows[0][c]];
      const double expected = std::strtod(rows[f + 1][c].c_str(), nullptr);
      if (std::isnan(expected))
        EXPECT_TRUE(value.is_null()) << rows[0][c];
      else
        EXPECT_NEAR(value.get<double>(), expected, 1e-6 * std::max(1.0, std::abs(expected))) << rows[0][c];
    }
  }
  EXPECT_EQ(summary_of(live)["live"]["udp_json"]["sent"], 60);
}

/// The arguments of the messages oscdump printed for `address` ("TIMETAG ADDRESS TYPES ARGS..."),
/// with their type tags.
std::vector<std::pair<std::string, std::vector<std::string>>> oscdump_messages(const std::string& text,
                                                                               const std::string& address) {
  std::vector<std::pair<std::string, std::vector<std::string>>> messages;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string timetag, path, types;
    words >> timetag >> path >> types;
    if (path != address) continue;
    std::vector<std::string> arguments;
    for (std::string word; words >> word;) arguments.push_back(word);
    messages.emplace_back(types, arguments);
  }
  return messages;
}

TEST(LiveCommand, EveryPoseGoesOutAsAnOscMessageThatOscdumpReads) {
  S2KF_SKIP_UNDER_SANITIZERS();
  if (std::system("command -v oscdump > /dev/null") != 0)
    GTEST_SKIP() << "oscdump not found (Debian: apt-get install liblo-tools)";
  const fs::path dir = empty_scratch("live_osc");
  const int port = free_udp_port();
  ChildProcess oscdump({"oscdump", "-L", std::to_string(port)}, dir / "oscdump.txt");
  // oscdump listens once a probe sent to it comes out.
  ASSERT_TRUE(oscdump.wait_for_output(
      [&](const std::string& out) {
        std::system(("oscsend 127.0.0.1 " + std::to_string(port) + " /probe i 1").c_str());
        return out.find("/probe") != std::string::npos;
      },
      5))
      << oscdump.output();
  Server server(data_file("walk.c3d"), dir);
  const std::string live = (dir / "live").string();
  const CommandResult r = run_command("live " + server.address() + " --subject " + walk_subject() +
                                      " --frames 60 --backlog 100000 --formats csv --quiet --osc 127.0.0.1:" +
                                      std::to_string(port) + " --out " + live);
  ASSERT_EQ(r.status, 0) << r.output;
  const auto count = [](const std::string& out) { return oscdump_messages(out, "/s2kf/pose").size(); };
  oscdump.wait_for_output([&](const std::string& out) { return count(out) >= 60; }, 5);
  const auto messages = oscdump_messages(oscdump.output(), "/s2kf/pose");
  ASSERT_EQ(messages.size(), 60u) << oscdump.output().substr(0, 2000);
  const auto rows = csv_rows(read_text(live + ".csv"));
  ASSERT_EQ(rows.size(), 61u);
  ASSERT_EQ(rows[0].size(), 48u);  // frame, time, 6 root values, 40 joints
  // oscdump prints float32 values with 6 decimals: the CSV's values to float precision and that.
  const auto near = [](const std::string& printed, double expected) {
    const double value = std::strtod(printed.c_str(), nullptr);
    if (std::isnan(expected)) return std::isnan(value);
    return std::abs(value - expected) <= 6e-7 + 1.2e-7 * std::abs(expected);
  };
  for (std::size_t f = 0; f < messages.size(); ++f) {
    const auto& [types, arguments] = messages[f];
    ASSERT_EQ(types, "ifi" + std::string(46, 'f'));
    ASSERT_EQ(arguments.size(), 49u);
    EXPECT_EQ(arguments[0], std::to_string(f));
    EXPECT_TRUE(near(arguments[1], 0.01 * static_cast<double>(f))) << arguments[1];
    EXPECT_GT(std::stoi(arguments[2]), 40) << "visible markers";
    for (std::size_t c = 2; c < rows[0].size(); ++c)
      EXPECT_TRUE(near(arguments[c + 1], std::strtod(rows[f + 1][c].c_str(), nullptr)))
          << "frame " << f << " " << rows[0][c] << ": OSC " << arguments[c + 1] << ", CSV " << rows[f + 1][c];
  }
  const nlohmann::json summary = summary_of(live);
  EXPECT_EQ(summary["live"]["osc"]["sent"], 60);
  EXPECT_EQ(summary["live"]["osc"]["dropped"], 0);
}

// A browser of the live view that stops reading: the tracker neither waits for it nor queues
// frames for it; the browser skips frames and the run ends on time.
TEST(LiveCommand, SlowBrowserNeverHoldsTheTracker) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = empty_scratch("live_view_slow");
  Server server(data_file("walk.c3d"), dir);
  const std::string live = (dir / "live").string(), subject = walk_subject();
  const auto start = std::chrono::steady_clock::now();
  ChildProcess program({S2KF_CLI, "live", server.address(), "--subject", subject, "--frames", "150",
                        "--backlog", "100000", "--formats", "csv", "--quiet", "--view", "0", "--out", live},
                       dir / "live_output.txt");
  int port = 0;
  ASSERT_TRUE(program.wait_for_output(
      [&](const std::string& out) {
        const std::size_t at = out.find("http://127.0.0.1:");
        if (at == std::string::npos || out.find('/', at + 17) == std::string::npos) return false;
        port = std::stoi(out.substr(at + 17));
        return true;
      },
      10))
      << program.output();
  // A client with a tiny receive window that asks for the events and never reads them.
  const int client = socket(AF_INET, SOCK_STREAM, 0);
  const int tiny = 1024;
  setsockopt(client, SOL_SOCKET, SO_RCVBUF, &tiny, sizeof tiny);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  ASSERT_EQ(connect(client, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  const std::string request = "GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  ASSERT_EQ(send(client, request.data(), request.size(), 0), static_cast<ssize_t>(request.size()));
  EXPECT_EQ(program.wait(), 0) << program.output();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  close(client);
  const nlohmann::json summary = summary_of(live);
  EXPECT_EQ(summary["frames"], 150);
  EXPECT_EQ(summary["live"]["frames_dropped_busy"], 0);
  EXPECT_EQ(summary["live"]["view"]["browsers"], 1);
  // How many frames the system's socket buffers took before the writes stalled depends on the
  // kernel; the newest-only rule bounds the rest: never more frames than were made.
  const nlohmann::json& view = summary["live"]["view"];
  EXPECT_LE(view["frames_sent"].get<long>() + view["frames_skipped"].get<long>(), 150) << view.dump();
  // 1.5 s of stream, the first second's preparation, the 2 s the view gives a stalled browser and
  // the second it waits for browsers to take the end; the rest is the loaded machine's margin.
  EXPECT_LT(seconds, 12.0);
  std::cout << "a browser that never reads: " << summary["live"]["view"].dump() << ", " << seconds
            << " s from start to exit\n";
}

TEST(LiveCommand, LiveViewOnATakenPortIsOneSentence) {
  const fs::path dir = empty_scratch("live_view_taken");
  Server server(data_file("walk.c3d"), dir);  // its port is taken
  const std::string port = std::to_string(server.port());
  const CommandResult r =
      run_command("live " + server.address() + " --view " + port + " --out " + (dir / "x").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "s2kf: --view: cannot serve on 127.0.0.1:" + port +
                          " (the port is taken, or the address is not one of this machine's)\n");
  EXPECT_FALSE(fs::exists(dir / "x.csv"));
}

TEST(LiveCommand, AFewFramesAreEnoughWithoutACalibration) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = empty_scratch("live_few");
  Server server(data_file("walk.c3d"), dir, {"--loop"});  // serves the second run too
  const std::string live = (dir / "live").string();
  CommandResult r = run_command("live " + server.address() + " --subject " + walk_subject() +
                                " --frames 5 --formats csv --quiet --out " + live);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(csv_rows(read_text(live + ".csv")).size(), 6u);
  r = run_command("live " + server.address() + " --frames 5 --formats csv --quiet --out " + live +
                  "_calibrated");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "s2kf: " + server.address() +
                          ": the calibration needs at least 10 frames, the stream gave 5 (give --subject or "
                          "--no-calibrate)\n");
}

TEST(LiveCommand, ReconnectsAfterALostConnectionAndKeepsTheFrames) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = empty_scratch("live_reconnect");
  Server server(data_file("walk.c3d"), dir, {"--fault-disconnect-after", "60"});
  const std::string live = (dir / "live").string();
  const CommandResult r = run_command("live " + server.address() + " --subject " + walk_subject() +
                                      " --frames 200 --backlog 100000 --formats csv --out " + live);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("connection lost"), std::string::npos) << r.output;
  const nlohmann::json summary = summary_of(live);
  EXPECT_EQ(summary["live"]["reconnects"], 1);
  EXPECT_EQ(summary["frames"], 200);
  EXPECT_EQ(csv_rows(read_text(live + ".csv")).size(), 201u);
}

TEST(LiveCommand, SkippedNumbersAndChangedLabelsAreReported) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = empty_scratch("live_faults");
  Server server(data_file("walk.c3d"), dir, {"--fault-skip-every", "10", "--fault-relabel-after", "30"});
  const std::string live = (dir / "live").string();
  const CommandResult r = run_command("live " + server.address() + " --subject " + walk_subject() +
                                      " --frames 150 --backlog 100000 --formats csv --quiet --out " + live);
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json summary = summary_of(live);
  // Numbers 10, 20, ..., 150 never came; frames without markers took their places.
  EXPECT_EQ(summary["live"]["frames_missing"], 15);
  EXPECT_EQ(summary["live"]["frames_filled"], 15);
  ASSERT_EQ(summary["live"]["label_changes"].size(), 1u);
  EXPECT_EQ(summary["frames"], 150);
}

TEST(LiveCommand, MalformedPacketEndsWithAClearErrorAndKeepsTheFrames) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = empty_scratch("live_malformed");
  Server server(data_file("walk.c3d"), dir, {"--fault-malformed-after", "120"});
  const std::string live = (dir / "live").string();
  const CommandResult r = run_command("live " + server.address() + " --subject " + walk_subject() +
                                      " --backlog 100000 --formats csv --quiet --out " + live);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output,
            "s2kf: " + server.address() +
                ": malformed stream, connection closed: a packet declares 1048577 bytes, more than the "
                "1048576 accepted; the 120 frames tracked until then are written\n");
  EXPECT_EQ(csv_rows(read_text(live + ".csv")).size(), 121u);
}

TEST(LiveCommand, CtrlCEndsTheStreamAndWritesTheFrames) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = empty_scratch("live_interrupt");
  Server server(data_file("walk.c3d"), dir, {"--loop"});
  const std::string live = (dir / "live").string();
  // The interrupt comes once 150 poses have gone out (over UDP), however busy the machine is.
  const UdpReceiver receiver;
  ASSERT_GT(receiver.port, 0);
  std::vector<std::string> arguments{
      S2KF_CLI,    "live",         server.address(),
      "--subject", walk_subject(), "--formats",
      "csv",       "--quiet",      "--out",
      live,        "--udp-json",   "127.0.0.1:" + std::to_string(receiver.port)};
  std::vector<char*> argv;
  for (std::string& a : arguments) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, S2KF_CLI, nullptr, nullptr, argv.data(), environ), 0);
  int poses = 0;
  for (std::string datagram; poses < 150 && receiver.receive(datagram, 60000);) ++poses;
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  ASSERT_EQ(poses, 150) << "no pose came for a minute";
  const nlohmann::json summary = summary_of(live);
  EXPECT_EQ(summary["live"]["end"], "stopped by a signal");
  EXPECT_GE(summary["frames"].get<long>(), 150);
  EXPECT_EQ(csv_rows(read_text(live + ".csv")).size(), summary["frames"].get<std::size_t>() + 1);
}

TEST(LiveCommand, RefusedConnectionIsOneSentenceAndStatusOne) {
  const fs::path dir = empty_scratch("live_refused");
  // A port that was just free: nothing listens on it.
  int port = 0;
  {
    Server server(data_file("walk.c3d"), dir);
    port = std::stoi(server.address().substr(server.address().find(':') + 1));
  }
  const CommandResult r =
      run_command("live 127.0.0.1:" + std::to_string(port) + " --out " + (dir / "x").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "s2kf: cannot connect to 127.0.0.1:" + std::to_string(port) + ": Connection refused\n");
  EXPECT_FALSE(fs::exists(dir / "x.csv"));
  const CommandResult bad = run_command("live 127.0.0.1:99999");
  EXPECT_EQ(bad.status, 1);
  EXPECT_EQ(bad.output, "s2kf: the port in 127.0.0.1:99999 is not 1 to 65535\n");
}

}  // namespace
