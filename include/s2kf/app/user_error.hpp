/// @file
/// The error a front end reports as one sentence: caused by what the user asked for (a bad option,
/// an unreadable file), not by a fault of the software.
#pragma once

#include <stdexcept>

namespace s2kf::app {

/// The program prints it and exits with status 1; the Python module raises ValueError (or
/// FileNotFoundError for a missing file).
struct UserError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace s2kf::app
