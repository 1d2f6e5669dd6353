/// @file
/// The subcommand registry of the s2kf program: each command_*.cpp registers itself, so adding a
/// subcommand never touches main.cpp.
#pragma once

#include "front_end.hpp"

#include <CLI/CLI.hpp>

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::cli {

struct Command {
  std::string name;
  std::string description;
  /// Adds the options to the subcommand and sets its callback.
  std::function<void(CLI::App&)> setup;
};

inline std::vector<Command>& registered_commands() {
  static std::vector<Command> commands;
  return commands;
}

struct RegisterCommand {
  RegisterCommand(std::string name, std::string description, std::function<void(CLI::App&)> setup) {
    registered_commands().push_back({std::move(name), std::move(description), std::move(setup)});
  }
};

}  // namespace s2kf::cli
