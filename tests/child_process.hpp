/// @file
/// Programs a test runs beside itself: a child process with its output in a file, ended with the
/// test (`s2kf serve`, `s2kf live` in the background, oscdump), and a UDP port the system chose.
#pragma once

#include "test_files.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace s2kf::test_support {

/// `arguments` (the program first, found on PATH) as a child process whose stdout and stderr go
/// to `output`; ended by SIGTERM with the object unless it has ended itself.
class ChildProcess {
 public:
  ChildProcess(std::vector<std::string> arguments, const std::filesystem::path& output) : output_(output) {
    std::vector<char*> argv;
    for (std::string& a : arguments) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    EXPECT_EQ(posix_spawnp(&pid_, argv[0], &actions, nullptr, argv.data(), environ), 0) << arguments[0];
    posix_spawn_file_actions_destroy(&actions);
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess() { stop(SIGTERM); }

  /// Sends `signal` (unless it has ended) and waits for the process; its exit status, or -1.
  int stop(int signal) {
    if (pid_ > 0) {
      if (!ended_) kill(pid_, signal);
      wait();
    }
    return status_;
  }
  /// Waits for the process to end by itself; its exit status, or -1.
  int wait() {
    if (pid_ > 0 && !ended_) {
      int raw = 0;
      waitpid(pid_, &raw, 0);
      ended_ = true;
      status_ = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    }
    return status_;
  }
  std::string output() const { return read_text(output_); }

  /// Polls the output (every 20 ms, up to `seconds`) until `done` says yes; false on time-out.
  bool wait_for_output(const std::function<bool(const std::string&)>& done, double seconds) const {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < until) {
      if (done(output())) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return done(output());
  }

 private:
  std::filesystem::path output_;
  pid_t pid_ = 0;
  bool ended_ = false;
  int status_ = -1;
};

#ifdef S2KF_CLI
/// `s2kf serve RECORDING --port 0 OPTIONS` as a child process, ended with the test.
class ServeProcess {
 public:
  ServeProcess(const std::string& recording, const std::filesystem::path& dir,
               const std::vector<std::string>& options = {}) {
    namespace fs = std::filesystem;
    const fs::path port_file = dir / "port";
    fs::remove(port_file);
    std::vector<std::string> arguments{S2KF_CLI, "serve",   recording,     "--port",
                                       "0",      "--quiet", "--port-file", port_file.string()};
    arguments.insert(arguments.end(), options.begin(), options.end());
    process_ = std::make_unique<ChildProcess>(arguments, dir / "serve_output.txt");
    for (int wait = 0; wait < 300 && !fs::exists(port_file); ++wait)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::ifstream(port_file) >> port_;
    EXPECT_GT(port_, 0) << "the server did not start";
  }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  int port() const { return port_; }

 private:
  std::unique_ptr<ChildProcess> process_;
  int port_ = 0;
};
#endif

/// A UDP port on 127.0.0.1 that the system has just chosen as free (for a program that must bind
/// it itself).
inline int free_udp_port() {
  const int s = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(s, reinterpret_cast<sockaddr*>(&address), sizeof address);
  socklen_t length = sizeof address;
  getsockname(s, reinterpret_cast<sockaddr*>(&address), &length);
  close(s);
  return ntohs(address.sin_port);
}

}  // namespace s2kf::test_support
