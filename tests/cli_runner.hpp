/// @file
/// Running the s2kf program from a test: its exit status and everything it printed (stdout and
/// stderr together).
#pragma once

#include "test_files.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace s2kf::test_support {

struct CommandResult {
  int status;  ///< exit status; -1 when the program did not exit normally
  std::string output;
};

#ifdef S2KF_CLI
/// Runs `S2KF_CLI arguments` through the shell (S2KF_CLI: the program, defined when it is built).
inline CommandResult run_command(const std::string& arguments) {
  const std::string command = std::string(S2KF_CLI) + " " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[4096];
  while (pipe && fgets(buffer, sizeof buffer, pipe)) output += buffer;
  const int status = pipe ? pclose(pipe) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

/// Simulates a recording with `s2kf simulate OPTIONS` into the scratch folder "sim"; returns the
/// prefix of its files (PREFIX.c3d, PREFIX_truth.csv, PREFIX_clean.csv).
inline std::string simulate_with_program(const std::string& name, const std::string& options) {
  const std::filesystem::path out = scratch("sim") / (name + ".c3d");
  const CommandResult r = run_command("simulate " + options + " --out " + out.string());
  EXPECT_EQ(r.status, 0) << r.output;
  return (scratch("sim") / name).string();
}
#endif

}  // namespace s2kf::test_support
