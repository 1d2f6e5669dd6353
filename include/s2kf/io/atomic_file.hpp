/// @file
/// Writing a file completely or not at all: the content goes to a temporary name beside the
/// target and is renamed over it only after every byte was written and flushed.
#pragma once

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

namespace s2kf::io {

/// Calls write(stream) on a temporary file next to `path`, then renames it to `path`. If write
/// throws or the stream fails, the temporary file is removed and a std::runtime_error naming the
/// file is thrown; an existing file at `path` is left as it was.
inline void write_file_atomically(const std::filesystem::path& path,
                                  const std::function<void(std::ostream&)>& write,
                                  std::ios::openmode mode = std::ios::out) {
  const std::filesystem::path temporary = path.string() + ".tmp";
  try {
    {
      std::ofstream stream(temporary, mode | std::ios::trunc);
      if (!stream) throw std::runtime_error("cannot open " + temporary.string() + " for writing");
      write(stream);
      stream.flush();
      if (!stream)
        throw std::runtime_error("cannot write " + path.string() + " (disk full or no permission?)");
    }
    std::error_code error;
    std::filesystem::rename(temporary, path, error);
    if (error)
      throw std::runtime_error("cannot rename " + temporary.string() + " to " + path.string() + ": " +
                               error.message());
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
}

}  // namespace s2kf::io
