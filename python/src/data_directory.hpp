/// @file
/// Where the module finds the bundled data (marker sets, motions): $S2KF_DATA_DIR, else the
/// source tree's data/ compiled in, the same rule the command-line program follows.
#pragma once

#include <cstdlib>
#include <filesystem>

namespace s2kf::python {

inline std::filesystem::path data_directory() {
  if (const char* from_environment = std::getenv("S2KF_DATA_DIR"); from_environment && *from_environment)
    return from_environment;
  return S2KF_DATA_DIR;
}

}  // namespace s2kf::python
