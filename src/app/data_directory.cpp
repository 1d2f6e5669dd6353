// The bundled data's folder (app/data_directory.hpp).
#include <s2kf/app/data_directory.hpp>

#include <cstdlib>

namespace s2kf::app {

std::filesystem::path data_directory() {
  if (const char* from_environment = std::getenv("S2KF_DATA_DIR"); from_environment && *from_environment)
    return from_environment;
  return S2KF_DATA_DIR;  // the source tree's data/, set by CMake
}

}  // namespace s2kf::app
