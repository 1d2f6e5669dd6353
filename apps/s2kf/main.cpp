// The s2kf command-line program: dispatches to the registered subcommands.
#include "command.hpp"
#include "interruption.hpp"

#include <s2kf/core/instruction_set.hpp>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <iostream>

namespace {

/// The subcommand the user was running ("s2kf track"), or "s2kf" before one was named.
std::string command_in_use(const CLI::App& app) {
  for (const CLI::App* sub : app.get_subcommands()) return "s2kf " + sub->get_name();
  return "s2kf";
}

/// CLI11's message as one sentence: its own text, ending with where the options are explained.
std::string parse_error_sentence(const CLI::ParseError& e, const CLI::App& app) {
  std::string message = e.what();
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ' || message.back() == '.'))
    message.pop_back();
  std::replace(message.begin(), message.end(), '\n', ' ');
  return message + " (see " + command_in_use(app) + " --help).";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "s2kf: whole-body motion tracking from optical motion capture with the Smart Sampling "
      "Kalman Filter"};
  // The version and the kernel variant the processor runs (core/instruction_set.hpp).
  app.set_version_flag(
      "--version", [] { return std::string("s2kf ") + S2KF_VERSION + ", " + s2kf::instruction_set_text(); });
  app.require_subcommand(1);
  auto commands = s2kf::cli::registered_commands();
  std::sort(commands.begin(), commands.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  for (const auto& command : commands) {
    CLI::App* sub = app.add_subcommand(command.name, command.description);
    command.setup(*sub);
  }
  // CLI11 would call an unknown command a missing one ("A subcommand is required").
  if (argc > 1 && argv[1][0] != '-' &&
      std::none_of(commands.begin(), commands.end(), [&](const auto& c) { return c.name == argv[1]; })) {
    std::string names;
    for (const auto& command : commands) names += (names.empty() ? "" : ", ") + command.name;
    std::cerr << "s2kf: there is no command " << argv[1] << " (the commands are " << names << ").\n";
    return 1;
  }
  s2kf::cli::install_interrupt_handlers();
  try {
    s2kf::active_instruction_set();  // a wrong S2KF_SIMD is an error before any work
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --version
  } catch (const CLI::ParseError& e) {
    // The README promises one sentence and status 1 for every user error, CLI11's included.
    std::cerr << "s2kf: " << parse_error_sentence(e, app) << "\n";
    return 1;
  } catch (const s2kf::cli::Interrupted& e) {
    std::cerr << "s2kf: " << e.what() << "\n";
    return 128 + e.signal;
  } catch (const std::exception& e) {
    std::cerr << "s2kf: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
