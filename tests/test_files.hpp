/// @file
/// Files in tests: the bundled data, a scratch folder per test under the build tree, and reading
/// back what a test wrote.
#pragma once

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace s2kf::test_support {

/// This test program's scratch folder under the build tree (tmp_<area>, one per program, so that
/// programs never share a file; ctest also runs each test of a program as a process of its own,
/// side by side, so the tests of one program name their files apart). Defined in a file CMake generates for
/// each program, not by a definition on the command line: every test program then has the same definitions
/// and can share one precompiled header.
const char* tmp_dir();

/// A file of the repository's data/ folder.
inline std::string data_file(const std::string& name) { return std::string(S2KF_DATA_DIR) + "/" + name; }

/// A scratch folder `name` under the build tree, created if absent (earlier files stay).
inline std::filesystem::path scratch(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(tmp_dir()) / name;
  std::filesystem::create_directories(dir);
  return dir;
}

/// A fresh, empty scratch folder `name`.
inline std::filesystem::path empty_scratch(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(tmp_dir()) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// Frames of the bundled recordings data/walk.c3d and data/handstand.c3d.
inline constexpr std::size_t kWalkFrames = 551, kHandstandFrames = 675;

/// The lines of a text, without their line ends.
inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// The whole text of a file ("" when it cannot be read).
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The names of the entries of a folder, sorted.
inline std::vector<std::string> file_names(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

/// The rows of a comma-separated text, each split into its fields (no quoting).
inline std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<std::string> fields;
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) fields.push_back(cell);
    rows.push_back(fields);
  }
  return rows;
}

}  // namespace s2kf::test_support
