/// @file
/// The exception the C3D reader and writer throw for a file they cannot use: it names the file,
/// the byte where the trouble is, and says what is wrong in a sentence a user understands.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace s2kf::c3d {

/// Thrown when a C3D file cannot be read at all (empty, not C3D, unknown processor, no data
/// section) or cannot be written. Damage a reader can work around (a truncated data section, a
/// wrong offset in the parameter section, disagreeing counts) is reported as a warning instead.
///
/// what() reads "<file name>: <sentence>", e.g. "Empty.c3d: not a C3D file: the file is empty".
class C3dError : public std::runtime_error {
 public:
  /// `file` is the path (or the name given to an in-memory buffer); `byte_offset` is the position
  /// in the file the sentence refers to, or -1 when it refers to no particular byte.
  C3dError(const std::string& file, std::int64_t byte_offset, const std::string& sentence)
      : std::runtime_error(display_name(file) + ": " + sentence),
        file_(file),
        byte_offset_(byte_offset),
        sentence_(sentence) {}

  /// The path or buffer name as given to the reader or writer.
  const std::string& file() const noexcept { return file_; }
  /// The byte the message is about, or -1.
  std::int64_t byte_offset() const noexcept { return byte_offset_; }
  /// The message without the file name.
  const std::string& sentence() const noexcept { return sentence_; }

 private:
  static std::string display_name(const std::string& file) {
    // The last path component is what a user recognises; the full path stays in file().
    const std::string name = std::filesystem::path(file).filename().string();
    return name.empty() ? file : name;
  }

  std::string file_;
  std::int64_t byte_offset_;
  std::string sentence_;
};

}  // namespace s2kf::c3d
