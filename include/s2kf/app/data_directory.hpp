/// @file
/// Where the bundled data (marker sets, motions) is found: $S2KF_DATA_DIR, else the data/ folder
/// of the source tree, compiled in.
#pragma once

#include <filesystem>

namespace s2kf::app {

std::filesystem::path data_directory();

}  // namespace s2kf::app
