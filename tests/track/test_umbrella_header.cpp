// The umbrella header s2kf/s2kf.hpp includes every public header of the library: a header added
// without it fails here, because this test lists the include directory itself.
#include <s2kf/s2kf.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

TEST(UmbrellaHeader, IncludesEveryPublicHeader) {
  const fs::path include = fs::path(S2KF_SOURCE_DIR) / "include";
  std::ifstream umbrella(include / "s2kf" / "s2kf.hpp");
  ASSERT_TRUE(umbrella) << "cannot open the umbrella header";
  std::stringstream text;
  text << umbrella.rdbuf();
  int headers = 0;
  for (const auto& entry : fs::recursive_directory_iterator(include / "s2kf")) {
    const fs::path path = entry.path();
    if (path.extension() != ".hpp" || path.filename() == "s2kf.hpp") continue;
    // The application layer needs nlohmann-json and is not part of the header-only library.
    if (path.parent_path().filename() == "app") continue;
    const std::string relative = fs::relative(path, include).generic_string();
    EXPECT_NE(text.str().find("#include <" + relative + ">"), std::string::npos) << relative;
    ++headers;
  }
  EXPECT_GT(headers, 40);
}

}  // namespace
