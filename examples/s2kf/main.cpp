// The s2kf command-line program: dispatches to the registered subcommands.
#include "command.hpp"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <iostream>

int main(int argc, char** argv) {
  CLI::App app{
      "s2kf: whole-body motion tracking from optical motion capture with the Smart Sampling "
      "Kalman Filter"};
  app.set_version_flag("--version", std::string("s2kf ") + S2KF_VERSION);
  app.require_subcommand(1);
  auto commands = s2kf::cli::registered_commands();
  std::sort(commands.begin(), commands.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  for (const auto& command : commands) {
    CLI::App* sub = app.add_subcommand(command.name, command.description);
    command.setup(*sub);
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "s2kf: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
