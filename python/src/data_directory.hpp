/// @file
/// Where an installed module finds the bundled data: a wheel from `pip install .` carries it in
/// s2kf_data/ beside the module's shared object, which use_installed_data() makes the default of
/// app::data_directory() ($S2KF_DATA_DIR, else the source tree's data/ compiled in).
#pragma once

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace s2kf::python {

/// Sets $S2KF_DATA_DIR to the s2kf_data/ folder beside this module's shared object when that folder
/// exists and the variable is unset: the module's C++ code (marker sets, motions) reads the variable,
/// and a wheel cannot know at compile time where it will be installed.
inline void use_installed_data() {
  if (const char* set = std::getenv("S2KF_DATA_DIR"); set && *set) return;
  Dl_info self{};
  if (dladdr(reinterpret_cast<const void*>(&use_installed_data), &self) == 0 || self.dli_fname == nullptr)
    return;
  std::error_code error;
  const std::filesystem::path beside =
      std::filesystem::absolute(self.dli_fname, error).parent_path() / "s2kf_data";
  if (!error && std::filesystem::is_directory(beside / "markersets", error))
    setenv("S2KF_DATA_DIR", beside.c_str(), 0);
}

}  // namespace s2kf::python
