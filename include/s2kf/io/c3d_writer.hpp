/// @file
/// Writing marker trajectories as C3D files (Intel, float storage, no analog data), frame by frame
/// or a whole Recording at once. The file appears under its name only when complete: it is
/// written to `path + ".tmp"` and renamed by finish().
#pragma once

#include <Eigen/Core>
#include <s2kf/core/compilation_mode.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <system_error>
#include <vector>

#include "s2kf/io/c3d_error.hpp"
#include "s2kf/io/c3d_reader.hpp"

namespace s2kf::c3d {

namespace detail {

/// Builds a parameter section (Intel byte order) and remembers where values a writer patches
/// later (frame counts, scale) live.
class ParameterSectionBuilder {
 public:
  void group(int id, const std::string& name) {
    begin_entry(-id, name);
    bytes_.push_back(0);  // no description
    end_entry();
  }

  /// Adds a numeric parameter; returns the byte offset of its first value in the section.
  std::size_t int16s(int group_id, const std::string& name, const std::vector<int>& dims,
                     const std::vector<std::uint16_t>& values) {
    begin_parameter(group_id, name, 2, dims);
    const std::size_t at = bytes_.size();
    for (std::uint16_t v : values) {
      bytes_.push_back(static_cast<std::uint8_t>(v & 0xFF));
      bytes_.push_back(static_cast<std::uint8_t>(v >> 8));
    }
    finish_parameter();
    return at;
  }

  std::size_t float32(int group_id, const std::string& name, float value) {
    begin_parameter(group_id, name, 4, {});
    const std::size_t at = bytes_.size();
    append_float(value);
    finish_parameter();
    return at;
  }

  /// A char array [length, count] of space-padded strings; a single string when `single`.
  void strings(int group_id, const std::string& name, const std::vector<std::string>& values,
               bool single = false) {
    std::size_t length = 1;
    for (const std::string& s : values) length = std::max(length, s.size());
    if (single)
      begin_parameter(group_id, name, -1, {static_cast<int>(length)});
    else
      begin_parameter(group_id, name, -1, {static_cast<int>(length), static_cast<int>(values.size())});
    for (const std::string& s : values) {
      bytes_.insert(bytes_.end(), s.begin(), s.end());
      bytes_.insert(bytes_.end(), length - s.size(), static_cast<std::uint8_t>(' '));
    }
    finish_parameter();
  }

  /// The section bytes after the 4-byte parameter header, ended by a zero name length and padded.
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

  void append_float(float value) {
    std::uint8_t raw[4];
    std::memcpy(raw, &value, 4);  // Intel files: IEEE little endian, as the host (checked below)
    bytes_.insert(bytes_.end(), raw, raw + 4);
  }

 private:
  void begin_entry(int id, const std::string& name) {
    entry_start_ = bytes_.size();
    bytes_.push_back(static_cast<std::uint8_t>(name.size()));
    bytes_.push_back(static_cast<std::uint8_t>(static_cast<std::int8_t>(id)));
    bytes_.insert(bytes_.end(), name.begin(), name.end());
    offset_at_ = bytes_.size();
    bytes_.push_back(0);
    bytes_.push_back(0);
  }
  void end_entry() {
    const std::size_t offset = bytes_.size() - offset_at_;  // from the offset field to the next entry
    bytes_[offset_at_] = static_cast<std::uint8_t>(offset & 0xFF);
    bytes_[offset_at_ + 1] = static_cast<std::uint8_t>(offset >> 8);
  }
  void begin_parameter(int group_id, const std::string& name, int type, const std::vector<int>& dims) {
    begin_entry(group_id, name);
    bytes_.push_back(static_cast<std::uint8_t>(static_cast<std::int8_t>(type)));
    bytes_.push_back(static_cast<std::uint8_t>(dims.size()));
    for (int d : dims) bytes_.push_back(static_cast<std::uint8_t>(d));
  }
  void finish_parameter() {
    bytes_.push_back(0);  // no description
    end_entry();
  }

  std::vector<std::uint8_t> bytes_;
  std::size_t entry_start_ = 0;
  std::size_t offset_at_ = 0;
};

inline void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v & 0xFF);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
inline void put_f32(std::uint8_t* p, float v) { std::memcpy(p, &v, 4); }

}  // namespace detail

/// Writes a C3D file frame by frame with constant memory. Nothing appears at `path` until
/// finish() succeeds; a writer destroyed without finish() (an exception, a crash of the
/// producer) removes its temporary file and leaves an existing `path` untouched.
///
/// Missing markers are stored as (0,0,0) with word 4 = -1.0f, visible ones with 0.0f. A visible
/// marker exactly at (0,0,0) reads back as missing: C3D readers treat the origin as a gap.
class C3dStreamWriter {
 public:
  /// `labels` (at most 65535, each at most 255 characters) fix the number of points;
  /// `rate` is in frames per second; `descriptions` is empty or one per label.
  C3dStreamWriter(std::string path, std::vector<std::string> labels, double rate,
                  std::vector<std::string> descriptions = {})
      : path_(std::move(path)), temporary_(path_ + ".tmp"), points_(static_cast<int>(labels.size())) {
    static_assert(std::numeric_limits<float>::is_iec559, "the writer stores IEEE floats");
    if (labels.size() > 65535)
      fail("a C3D file holds at most 65535 points, got " + std::to_string(labels.size()));
    if (!descriptions.empty() && descriptions.size() != labels.size())
      fail(std::to_string(descriptions.size()) + " descriptions for " + std::to_string(labels.size()) +
           " labels");
    if (!(rate > 0.0) || !std::isfinite(rate))
      fail("the frame rate must be positive, got " + std::to_string(rate));
    for (const auto* list : {&labels, &descriptions})
      for (const std::string& s : *list)
        if (s.size() > 255)
          fail("label or description \"" + s.substr(0, 20) + "...\" is longer than 255 characters");
    if (descriptions.empty()) descriptions.assign(labels.size(), "");
    build_parameters(labels, descriptions, static_cast<float>(rate));
    file_.open(temporary_, std::ios::binary | std::ios::trunc);
    if (!file_) fail("cannot open " + temporary_ + " for writing");
    file_.write(reinterpret_cast<const char*>(head_.data()), static_cast<std::streamsize>(head_.size()));
    frame_.resize(static_cast<std::size_t>(points_) * 16);
    check_stream();
  }

  C3dStreamWriter(const C3dStreamWriter&) = delete;
  C3dStreamWriter& operator=(const C3dStreamWriter&) = delete;

  ~C3dStreamWriter() {
    if (!finished_) {
      file_.close();
      std::error_code ignored;
      std::filesystem::remove(temporary_, ignored);
    }
  }

  int point_count() const { return points_; }
  std::int64_t frames_written() const { return frames_; }

  /// Appends one frame: column p of `positions` is point p in mm; a point is missing where
  /// `visible` is false or a coordinate is not finite.
  void append(const Eigen::Ref<const Eigen::Matrix3Xd>& positions,
              const Eigen::Ref<const Eigen::Array<bool, Eigen::Dynamic, 1>>& visible);

  /// Appends one frame in which exactly the points with non-finite coordinates are missing.
  void append(const Eigen::Ref<const Eigen::Matrix3Xd>& positions) {
    if (positions.cols() != points_)
      fail("a frame of " + std::to_string(positions.cols()) + " points for a file of " +
           std::to_string(points_) + " points");
    append_columns(positions.data(), positions.outerStride(), nullptr);
  }

  /// Completes the counts in header and parameters, then renames the temporary file to `path`.
  void finish();

 private:
  [[noreturn]] void fail(const std::string& sentence) {
    if (file_.is_open()) file_.close();
    std::error_code ignored;
    std::filesystem::remove(temporary_, ignored);
    throw C3dError(path_, -1, sentence);
  }

  void check_stream() {
    if (!file_) fail("cannot write " + temporary_ + " (disk full or no permission?)");
  }

  void patch(std::int64_t at, const std::uint8_t* bytes, int count) {
    file_.seekp(at);
    file_.write(reinterpret_cast<const char*>(bytes), count);
    check_stream();
  }

  void append_columns(const double* xyz, Eigen::Index stride, const bool* visible);

  void build_parameters(const std::vector<std::string>& labels, const std::vector<std::string>& descriptions,
                        float rate) {
    constexpr int point = 1, analog = 2, trial = 3;
    detail::ParameterSectionBuilder b;
    b.group(point, "POINT");
    b.int16s(point, "USED", {}, {static_cast<std::uint16_t>(points_)});
    scale_at_ = b.float32(point, "SCALE", -1.0f / 32000.0f);
    b.float32(point, "RATE", rate);
    const std::size_t data_start_at = b.int16s(point, "DATA_START", {}, {0});
    frames_at_ = b.int16s(point, "FRAMES", {}, {0});
    long_frames_at_ = b.float32(point, "LONG_FRAMES", 0.0f);
    // At most 255 strings per parameter; LABELS2, LABELS3, ... continue the list.
    for (const auto& [base, list] :
         {std::pair<const char*, const std::vector<std::string>*>{"LABELS", &labels},
          {"DESCRIPTIONS", &descriptions}}) {
      std::size_t start = 0;
      int part = 1;
      do {
        const std::size_t end = std::min(list->size(), start + 255);
        b.strings(point, part == 1 ? base : base + std::to_string(part),
                  std::vector<std::string>(list->begin() + static_cast<std::ptrdiff_t>(start),
                                           list->begin() + static_cast<std::ptrdiff_t>(end)));
        start = end;
        ++part;
      } while (start < list->size());
    }
    b.strings(point, "UNITS", {"mm"}, true);
    b.group(analog, "ANALOG");
    b.int16s(analog, "USED", {}, {0});
    b.float32(analog, "RATE", rate);
    b.group(trial, "TRIAL");
    b.int16s(trial, "ACTUAL_START_FIELD", {2}, {1, 0});
    end_field_at_ = b.int16s(trial, "ACTUAL_END_FIELD", {2}, {0, 0});

    // The section: 4-byte header, the entries, a zero name length, zero padding to a block.
    const std::size_t section_bytes = 4 + b.bytes().size() + 2;
    const std::size_t blocks = (section_bytes + 511) / 512;
    if (blocks + 2 > 65535) fail("the labels need more parameter blocks than a C3D file can address");
    const std::uint16_t data_start = static_cast<std::uint16_t>(2 + blocks);
    parameters_at_ = 512 + 4;
    head_.assign(512 + blocks * 512, 0);
    std::uint8_t* h = head_.data();
    h[0] = 2;
    h[1] = 0x50;
    detail::put_u16(h + 2, static_cast<std::uint16_t>(points_));
    detail::put_u16(h + 4, 0);  // analog values per frame
    detail::put_u16(h + 6, 1);  // first frame
    detail::put_u16(h + 8, 0);  // last frame, patched by finish()
    detail::put_u16(h + 10, 0);
    detail::put_f32(h + 12, -1.0f / 32000.0f);
    detail::put_u16(h + 16, data_start);
    detail::put_u16(h + 18, 0);
    detail::put_f32(h + 20, rate);
    std::uint8_t* p = h + 512;
    p[0] = 1;
    p[1] = 0x50;
    p[2] = static_cast<std::uint8_t>(std::min<std::size_t>(blocks, 255));  // readers do not rely on it
    p[3] = 84;                                                             // Intel
    std::copy(b.bytes().begin(), b.bytes().end(), p + 4);
    detail::put_u16(p + 4 + data_start_at, data_start);
  }

  std::string path_;
  std::string temporary_;
  int points_;
  std::ofstream file_;
  std::vector<std::uint8_t> head_;   // header and parameter blocks
  std::vector<std::uint8_t> frame_;  // one frame of point words
  std::int64_t parameters_at_ = 0;   // file offset of the first parameter entry
  std::size_t scale_at_ = 0, frames_at_ = 0, long_frames_at_ = 0, end_field_at_ = 0;
  std::int64_t frames_ = 0;
  double max_abs_ = 0.0;
  bool finished_ = false;
};

/// The label a writer stores for a point: "subject:name" or "name".
inline std::string stored_label(const PointLabel& label) {
  return label.subject.empty() ? label.name : label.subject + ":" + label.name;
}

/// Writes 3P x F `positions` (mm; NaN or visible == false means missing; `visible` P x F or
/// empty) with one label per point.
void write_c3d(const std::string& path, const std::vector<std::string>& labels, double rate,
               const Eigen::MatrixXd& positions,
               const Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>& visible = {},
               const std::vector<std::string>& descriptions = {});

/// Writes a Recording (as read by read_c3d, or built by a simulator) with its labels and rate.
void write_c3d(const std::string& path, const Recording& recording);

}  // namespace s2kf::c3d

#if !defined(S2KF_COMPILED)
#include <s2kf/io/c3d_writer.hxx>
#endif
