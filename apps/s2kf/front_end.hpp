/// @file
/// The program is a front end of the application layer (include/s2kf/app/): its marker sets,
/// summaries, output files and errors (app::UserError: one sentence, exit status 1) are the program's.
/// Files that register no subcommand include this instead of command.hpp, and so compile without
/// CLI11 (whose header alone is ~3.5 s of code generation per file).
#pragma once

#include <s2kf/app/user_error.hpp>

namespace s2kf::cli {

using namespace s2kf::app;

}  // namespace s2kf::cli
