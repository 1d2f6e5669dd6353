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
#include <system_error>
#include <utility>

namespace s2kf::io {

/// A file written piece by piece that appears under its name only when complete: stream() writes to
/// `path + ".tmp"`, commit() renames that over `path`. Destroyed without commit() (an exception, an
/// abandoned run), it removes the temporary file and leaves an existing file at `path` as it was.
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::filesystem::path path, std::ios::openmode mode = std::ios::out)
      : path_(std::move(path)), temporary_(path_.string() + ".tmp") {
    stream_.open(temporary_, mode | std::ios::out | std::ios::trunc);
    if (!stream_) throw std::runtime_error("cannot open " + temporary_.string() + " for writing");
  }
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  ~AtomicFileWriter() { discard(); }

  std::ostream& stream() { return stream_; }
  const std::filesystem::path& path() const { return path_; }
  const std::filesystem::path& temporary_path() const { return temporary_; }
  bool committed() const { return committed_; }

  /// Throws std::runtime_error naming the file if a write failed so far (disk full, no permission).
  void check() const {
    if (!stream_)
      throw std::runtime_error("cannot write " + path_.string() + " (disk full or no permission?)");
  }

  /// Flushes and closes the temporary file and renames it to path(). On failure the temporary file
  /// is removed and a std::runtime_error naming the file is thrown.
  void commit() {
    if (committed_) return;
    try {
      if (!stream_.is_open())
        throw std::runtime_error("cannot write " + path_.string() + ": already discarded");
      stream_.flush();
      check();
      stream_.close();
      if (stream_.fail()) throw std::runtime_error("cannot close " + temporary_.string());
      std::error_code error;
      std::filesystem::rename(temporary_, path_, error);
      if (error)
        throw std::runtime_error("cannot rename " + temporary_.string() + " to " + path_.string() + ": " +
                                 error.message());
      committed_ = true;
    } catch (...) {
      discard();
      throw;
    }
  }

  /// Closes and removes the temporary file (nothing when committed).
  void discard() noexcept {
    if (committed_) return;
    if (stream_.is_open()) stream_.close();
    std::error_code ignored;
    std::filesystem::remove(temporary_, ignored);
  }

 private:
  std::filesystem::path path_;
  std::filesystem::path temporary_;
  std::ofstream stream_;
  bool committed_ = false;
};

/// Calls write(stream) on a temporary file next to `path`, then renames it to `path`. If write
/// throws or the stream fails, the temporary file is removed and a std::runtime_error naming the
/// file is thrown; an existing file at `path` is left as it was.
inline void write_file_atomically(const std::filesystem::path& path,
                                  const std::function<void(std::ostream&)>& write,
                                  std::ios::openmode mode = std::ios::out) {
  AtomicFileWriter file(path, mode);
  write(file.stream());
  file.commit();
}

}  // namespace s2kf::io
