/// @file
/// Reading C3D motion capture files from Intel, DEC and MIPS writers, integer or float storage,
/// as a stream of frames with constant memory or as a whole recording. It survives the damaged and
/// inconsistent files real systems write (docs/c3d.md lists the traps it handles) and
/// reports what it had to work around as warnings; only a file it cannot read at all throws C3dError.
#pragma once

#include <Eigen/Core>
#include <s2kf/core/compilation_mode.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <s2kf/body/label_text.hpp>
#include <s2kf/io/c3d_error.hpp>
#include <s2kf/io/marker_sequence.hpp>

namespace s2kf::c3d {

/// How the writing machine stored numbers (byte 4 of the parameter section, 83 + type).
enum class Processor { intel, dec, mips };
/// Marker coordinates as scaled int16 or as float32 (negative POINT:SCALE).
enum class StorageFormat { integer, floating };

inline const char* to_string(Processor processor) {
  switch (processor) {
    case Processor::intel:
      return "intel";
    case Processor::dec:
      return "dec";
    case Processor::mips:
      return "mips";
  }
  return "unknown";
}

inline const char* to_string(StorageFormat format) {
  return format == StorageFormat::integer ? "integer" : "float";
}

/// One point label as found in the file and the unique name the reader gives it.
struct PointLabel {
  /// Unique among the points of the same subject: the label without its subject prefix, or the
  /// description when Motion Analysis 4-character labels repeat, "LFHD_2" for a second "LFHD",
  /// "point_17" for an empty 17th label.
  std::string name;
  /// The part before the last ':' of the label ("Daphnee" in "Daphnee:ASISr"), else empty.
  std::string subject;
  /// The label as stored, blanks and NULs trimmed.
  std::string raw;
  /// Listed in POINT:ANGLES/FORCES/MOMENTS/POWERS/SCALARS/REACTIONS: a computed output, not a
  /// marker, so a tracker must ignore it.
  bool model_output = false;
};

/// How analog samples sit after the points of each frame (the reader skips them).
struct AnalogLayout {
  int channels = 0;           ///< ANALOG:USED (0 if absent)
  int samples_per_frame = 0;  ///< per channel and 3D frame
  int values_per_frame = 0;   ///< analog words stored per 3D frame
  double rate = 0.0;          ///< ANALOG:RATE, or the point rate times samples_per_frame
};

/// What the header and parameter section say, reconciled with the file size.
struct C3dInfo {
  Processor processor = Processor::intel;
  StorageFormat format = StorageFormat::floating;
  int point_count = 0;                    ///< points per frame of the layout that fits the file
  std::int64_t frame_count = 0;           ///< complete frames present in the file
  std::int64_t declared_frame_count = 0;  ///< what header and parameters claim
  int first_frame = 1;                    ///< header word 4, the raw (1-based) number of frame 0
  double rate = 0.0;                      ///< 3D frames per second
  std::string units;                      ///< POINT:UNITS as stored ("" when absent)
  double to_mm = 1.0;                     ///< factor that turns stored coordinates into mm
  double scale = 0.0;                     ///< header scale factor (negative for float storage)
  std::int64_t data_offset = 0;           ///< byte where frame 0 starts
  std::int64_t frame_bytes = 0;           ///< bytes per stored frame, points and analog
  std::string layout = "header";          ///< which candidate layout fits the file size
  std::vector<PointLabel> labels;         ///< one per point, in file order
  std::vector<std::string> descriptions;  ///< POINT:DESCRIPTIONS, one per point ("" if absent)
  AnalogLayout analog;
  std::vector<std::string> warnings;  ///< everything the reader had to work around
};

/// One parameter of the parameter section, decoded to host numbers.
struct Parameter {
  std::string group;  ///< upper case
  std::string name;   ///< upper case
  int type = 0;       ///< -1 char, 1 byte, 2 int16, 4 float32
  std::vector<int> dimensions;
  std::vector<double> numbers;       ///< type 1 (unsigned), 2 (signed), 4; column-major
  std::vector<std::string> strings;  ///< type -1: dims[0] is the length, trimmed
  std::vector<std::uint16_t> words;  ///< type 2 as unsigned 16-bit words (counts are unsigned)
  std::string description;
  bool locked = false;
};

/// One frame of marker positions (0-based index among the stored frames).
using Frame = MarkerFrame;

/// All frames of a file: the marker data (labels as in marker_labels(info)) and what the file says.
struct Recording : MarkerSequence {
  C3dInfo info;
};

/// The labels a C3D file's points are matched by: their names (subject prefix kept), with model
/// outputs (angles, forces, ... that Vicon stores as points) as empty strings, which match nothing.
inline std::vector<std::string> marker_labels(const C3dInfo& info) {
  std::vector<std::string> labels;
  for (const PointLabel& label : info.labels)
    labels.push_back(label.model_output ? std::string() : label.name);
  return labels;
}

/// The frame rates motion capture runs at, in Hz (slow exports to high-speed cameras): a header
/// outside them (1e-40, 1e30) is corrupt, and tracking refuses it.
inline constexpr double kPlausibleFrameRateHz[2] = {1.0, 100000.0};
inline bool plausible_frame_rate(double hz) {
  return hz >= kPlausibleFrameRateHz[0] && hz <= kPlausibleFrameRateHz[1];
}

namespace detail {

/// Shortest decimal that reads back as the same float, for warnings a user compares with a hex dump.
inline std::string format_number(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

/// Number decoding in the byte order and float format of the file's processor.
class Decoder {
 public:
  explicit Decoder(Processor processor = Processor::intel) : processor_(processor) {}

  std::uint16_t u16(const std::uint8_t* p) const {
    return processor_ == Processor::mips ? static_cast<std::uint16_t>((p[0] << 8) | p[1])
                                         : static_cast<std::uint16_t>(p[0] | (p[1] << 8));
  }
  std::int16_t i16(const std::uint8_t* p) const { return static_cast<std::int16_t>(u16(p)); }

  float f32(const std::uint8_t* p) const {
    std::uint32_t bits = 0;
    switch (processor_) {
      case Processor::intel:
        bits = std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) |
               (std::uint32_t(p[3]) << 24);
        break;
      case Processor::mips:
        bits = std::uint32_t(p[3]) | (std::uint32_t(p[2]) << 8) | (std::uint32_t(p[1]) << 16) |
               (std::uint32_t(p[0]) << 24);
        break;
      case Processor::dec: {
        // VAX F: the 16-bit halves are swapped relative to IEEE little endian and the exponent is
        // biased by 2 more; an exponent field of 0 is zero whatever the sign and mantissa.
        bits = std::uint32_t(p[2]) | (std::uint32_t(p[3]) << 8) | (std::uint32_t(p[0]) << 16) |
               (std::uint32_t(p[1]) << 24);
        if ((bits & 0x7F800000u) == 0) return 0.0f;
        float value;
        std::memcpy(&value, &bits, 4);
        return value / 4.0f;
      }
    }
    float value;
    std::memcpy(&value, &bits, 4);
    return value;
  }

 private:
  Processor processor_;
};

/// Float word 4: the spec's rule validated on 198 real files. Negative or non-finite means
/// missing; below 65536 the int16 sign bit (bit 15) means missing, which catches the 65535.0
/// convention; larger values (Biogesta's 1.7e38) are valid with an unknown residual.
inline bool float_residual_missing(float w) {
  if (!(w >= 0.0f)) return true;  // negative or NaN
  if (!std::isfinite(w)) return true;
  if (w < 65536.0f) return (static_cast<std::int32_t>(w) & 0x8000) != 0;
  return false;
}

/// Coordinates that mean "no marker" although the residual says otherwise. (0,0,0) counts only
/// for markers: a computed output such as a power can legitimately be zero.
inline bool sentinel_coordinates(double x, double y, double z, bool zero_is_missing) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return true;
  if (zero_is_missing && x == 0.0 && y == 0.0 && z == 0.0) return true;
  // Motion Analysis Cortex 2.1.1 writes 9999999 for occluded markers.
  constexpr double cortex_occluded = 9999998.5;
  return std::abs(x) >= cortex_occluded || std::abs(y) >= cortex_occluded || std::abs(z) >= cortex_occluded;
}

}  // namespace detail

/// Reads a C3D file. Construction parses the header and parameter section and decides the frame
/// layout; frames are then read in order (or from a chosen frame) with one frame buffer, so
/// memory stays constant however long the recording is.
class C3dReader {
 public:
  /// Opens `path`; throws C3dError if the file cannot be opened or is not a readable C3D file.
  explicit C3dReader(const std::string& path) : name_(path) {
    if (std::filesystem::is_directory(path)) throw C3dError(path, -1, "a folder, not a C3D file");
    auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
    if (!*file) throw C3dError(path, -1, "cannot open the file for reading");
    stream_ = std::move(file);
    open();
  }

  /// Reads from any seekable stream, e.g. a std::istringstream over bytes in memory; `name` is
  /// used in warnings and errors.
  C3dReader(std::unique_ptr<std::istream> stream, std::string name)
      : name_(std::move(name)), stream_(std::move(stream)) {
    if (!stream_) throw C3dError(name_, -1, "no stream to read from");
    open();
  }

  const C3dInfo& info() const { return info_; }
  /// Every parameter found, in file order (repeated ones included).
  const std::vector<Parameter>& parameters() const { return parameters_; }
  /// The first parameter GROUP:NAME (case-insensitive), or nullptr.
  const Parameter* parameter(std::string_view group, std::string_view name) const;

  /// Index of the frame read_frame returns next.
  std::int64_t next_frame() const { return next_frame_; }

  /// Makes `index` (0-based, at most frame_count) the next frame to read.
  void seek_frame(std::int64_t index);

  /// Reads the next frame into `frame` (resized on first use, then reused); false at the end.
  bool read_frame(Frame& frame);

  /// Reads up to `max_frames` next frames into `positions` (3P x n, mm) and `visible` (P x n);
  /// returns n, 0 at the end.
  std::int64_t read_frames(std::int64_t max_frames, Eigen::MatrixXd& positions,
                           Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>& visible) {
    const std::int64_t n = std::max<std::int64_t>(0, std::min(max_frames, info_.frame_count - next_frame_));
    const int points = info_.point_count;
    positions.resize(3 * points, static_cast<Eigen::Index>(n));
    visible.resize(points, static_cast<Eigen::Index>(n));
    for (std::int64_t f = 0; f < n; ++f) load_next(positions.col(f).data(), visible.col(f).data());
    return n;
  }

 private:
  // ---------------------------------------------------------------- opening

  void open();

  void read_processor(std::uint8_t byte);

  // ---------------------------------------------------------------- parameters

  void parse_parameters(int declared_blocks, int header_data_start);

  static void decode_values(Parameter& parameter, const std::uint8_t* data, std::int64_t elements,
                            const detail::Decoder& d) {
    switch (parameter.type) {
      case -1: {
        // dims[0] is the string length, the rest count strings; one string when ndims <= 1.
        const std::int64_t length = parameter.dimensions.empty() ? 1 : parameter.dimensions[0];
        if (length == 0) return;
        const std::int64_t count = elements / length;
        parameter.strings.reserve(static_cast<std::size_t>(count));
        for (std::int64_t i = 0; i < count; ++i)
          parameter.strings.push_back(utf8_from_file_text(trim(std::string_view(
              reinterpret_cast<const char*>(data + i * length), static_cast<std::size_t>(length)))));
        return;
      }
      case 1:
        parameter.numbers.assign(data, data + elements);
        return;
      case 2:
        parameter.numbers.reserve(static_cast<std::size_t>(elements));
        parameter.words.reserve(static_cast<std::size_t>(elements));
        for (std::int64_t i = 0; i < elements; ++i) {
          parameter.words.push_back(d.u16(data + 2 * i));
          parameter.numbers.push_back(d.i16(data + 2 * i));
        }
        return;
      case 4:
        parameter.numbers.reserve(static_cast<std::size_t>(elements));
        for (std::int64_t i = 0; i < elements; ++i) parameter.numbers.push_back(d.f32(data + 4 * i));
        return;
      default:
        return;
    }
  }

  /// A count parameter as an unsigned value: int16 counts are uint16 (sample33 DATA_START 188,
  /// POINT:USED above 32767), floats are accepted when they are whole and non-negative.
  static bool unsigned_value(const Parameter* p, std::int64_t& value) {
    if (!p) return false;
    if (p->type == 2 && !p->words.empty()) {
      value = p->words[0];
      return true;
    }
    if (!p->numbers.empty()) {
      const double v = p->numbers[0];
      if (std::isfinite(v) && v >= 0.0 && v < 4.0e9) {
        value = static_cast<std::int64_t>(std::llround(v));
        return true;
      }
    }
    return false;
  }

  void read_units();

  /// The frame count the file claims, by c3d.org's "Reading the frame count": POINT:FRAMES unless
  /// it is 65535, then POINT:LONG_FRAMES or TRIAL:ACTUAL_START/END_FIELD; the header otherwise.
  /// Returns -1 when the count is saturated at 65535 with nothing better: the file size decides.
  std::int64_t declared_frames(int header_first, int header_last);

  int word_bytes() const { return info_.format == StorageFormat::floating ? 4 : 2; }

  void choose_layout(int header_points, int header_analog, int header_analog_per_frame,
                     const Parameter* point_used, const Parameter* analog_used, std::int64_t declared) {
    struct Candidate {
      const char* name;
      std::int64_t points;
      std::int64_t analog;
    };
    std::vector<Candidate> candidates{{"header", header_points, header_analog}};
    std::int64_t used_points = header_points;
    std::int64_t channels = 0;
    const bool have_points = unsigned_value(point_used, used_points);
    const bool have_channels = unsigned_value(analog_used, channels);
    if (have_points || have_channels) {
      candidates.push_back({"params*hdr_spf", used_points, channels * header_analog_per_frame});
      const Parameter* analog_rate = parameter("ANALOG", "RATE");
      if (analog_rate && !analog_rate->numbers.empty() && info_.rate > 0.0) {
        const double ratio = analog_rate->numbers[0] / info_.rate;
        if (std::isfinite(ratio) && ratio >= 0.0 && ratio < 65536.0)
          candidates.push_back(
              {"params*rate", used_points, channels * static_cast<std::int64_t>(std::lround(ratio))});
      }
    }
    const std::int64_t available = size_ - info_.data_offset;
    const auto frame_bytes = [&](const Candidate& c) { return (c.points * 4 + c.analog) * word_bytes(); };
    const Candidate* chosen = &candidates.front();
    if (declared >= 0) {
      for (const Candidate& c : candidates) {
        const std::int64_t fb = frame_bytes(c);
        if (fb <= 0) continue;
        // N frames fit exactly, allowing a partial trailing block of padding.
        if (declared <= available / fb && available - declared * fb < fb + 512) {
          chosen = &c;
          break;
        }
      }
    }
    if (chosen != &candidates.front())
      warn(std::string("frame layout from ") + chosen->name + " (points=" + std::to_string(chosen->points) +
           " analog/frame=" + std::to_string(chosen->analog) + ") fits file; header says points=" +
           std::to_string(header_points) + " analog/frame=" + std::to_string(header_analog));
    else if (have_points && used_points != header_points)
      warn("header says " + std::to_string(header_points) + " points, POINT:USED " +
           std::to_string(used_points) + "; the header is used");
    info_.layout = chosen->name;
    info_.point_count = static_cast<int>(chosen->points);
    info_.frame_bytes = frame_bytes(*chosen);
    info_.analog.values_per_frame = static_cast<int>(chosen->analog);
    info_.analog.channels = have_channels ? static_cast<int>(channels) : 0;
    info_.analog.samples_per_frame =
        info_.analog.channels > 0 ? info_.analog.values_per_frame / info_.analog.channels : 0;
    const Parameter* analog_rate = parameter("ANALOG", "RATE");
    info_.analog.rate = analog_rate && !analog_rate->numbers.empty()
                            ? analog_rate->numbers[0]
                            : info_.rate * info_.analog.samples_per_frame;

    if (info_.frame_bytes <= 0) {
      if (declared != 0) warn("frames hold neither points nor analog values; no frames are read");
      info_.frame_count = 0;
      return;
    }
    const std::int64_t fit = available / info_.frame_bytes;
    if (declared < 0) {
      warn("the frame count is stored as 65535 without POINT:LONG_FRAMES or TRIAL fields; " +
           std::to_string(fit) + " frames fit in the file");
      info_.declared_frame_count = fit;
      info_.frame_count = fit;
    } else if (fit < declared) {
      warn("declared " + std::to_string(declared) + " frames but only " + std::to_string(fit) +
           " fit in file");
      info_.frame_count = fit;
    } else {
      info_.frame_count = declared;
    }
  }

  // ---------------------------------------------------------------- labels

  std::vector<std::string> collect_strings(const std::string& base) const;

  void read_labels();

  // ---------------------------------------------------------------- frames

  void read_at(std::int64_t offset, std::uint8_t* data, std::int64_t count);

  void load_next(double* xyz, bool* visible);

  void decode_points(const std::uint8_t* data, double* xyz, bool* visible) const;

  void warn(std::string message) { info_.warnings.push_back(std::move(message)); }

  std::string name_;
  std::unique_ptr<std::istream> stream_;
  std::int64_t size_ = 0;
  std::int64_t parameter_offset_ = 0;
  C3dInfo info_;
  std::vector<Parameter> parameters_;
  std::vector<std::uint8_t> buffer_;           // one stored frame
  std::vector<std::uint8_t> zero_is_missing_;  // per point: 0 for model outputs
  std::int64_t next_frame_ = 0;
  bool positioned_ = false;
};

/// Reads every frame of `reader` from its current position into a Recording.
Recording read_all(C3dReader& reader);

/// Reads the whole file at `path`; throws C3dError if it is not a readable C3D file.
Recording read_c3d(const std::string& path);

}  // namespace s2kf::c3d

#if !defined(S2KF_COMPILED)
#include <s2kf/io/c3d_reader.hxx>
#endif
