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

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

S2KF_INLINE const Parameter* C3dReader::parameter(std::string_view group, std::string_view name) const {
  const std::string g = upper_case(std::string(group));
  const std::string n = upper_case(std::string(name));
  for (const Parameter& p : parameters_)
    if (p.group == g && p.name == n) return &p;
  return nullptr;
}

S2KF_INLINE void C3dReader::seek_frame(std::int64_t index) {
  if (index < 0 || index > info_.frame_count)
    throw C3dError(name_, -1,
                   "frame " + std::to_string(index) + " is outside the " + std::to_string(info_.frame_count) +
                       " frames of the file");
  next_frame_ = index;
  positioned_ = false;
}

S2KF_INLINE bool C3dReader::read_frame(Frame& frame) {
  if (next_frame_ >= info_.frame_count) return false;
  const int points = info_.point_count;
  if (frame.positions.cols() != points) frame.positions.resize(3, points);
  if (frame.visible.size() != points) frame.visible.resize(points);
  frame.index = next_frame_;
  load_next(frame.positions.data(), frame.visible.data());
  return true;
}

S2KF_INLINE void C3dReader::open() {
  stream_->seekg(0, std::ios::end);
  const std::streamoff end = stream_->tellg();
  if (!*stream_ || end < 0) throw C3dError(name_, -1, "cannot determine the file size");
  size_ = static_cast<std::int64_t>(end);
  if (size_ == 0) throw C3dError(name_, 0, "not a C3D file: the file is empty");
  if (size_ < 512)
    throw C3dError(
        name_, size_,
        "not a C3D file: it has " + std::to_string(size_) + " bytes, fewer than the 512-byte header block");
  std::array<std::uint8_t, 512> header{};
  read_at(0, header.data(), 512);
  if (header[1] != 0x50) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02X", header[1]);
    throw C3dError(name_, 1, std::string("not a C3D file: byte 1 is ") + hex + ", expected 0x50");
  }
  const int parameter_block = header[0];
  if (parameter_block == 0)
    throw C3dError(name_, 0,
                   "not a C3D file: byte 0 says the parameters start in block 0 (blocks count from 1)");
  parameter_offset_ = std::int64_t(parameter_block - 1) * 512;
  if (parameter_offset_ + 4 > size_)
    throw C3dError(name_, 0,
                   "the file ends before the parameter section in block " + std::to_string(parameter_block));
  std::array<std::uint8_t, 4> parameter_header{};
  read_at(parameter_offset_, parameter_header.data(), 4);
  read_processor(parameter_header[3]);
  const detail::Decoder d(info_.processor);

  // Header words, in the byte order and float format the processor byte announced.
  const int header_points = d.u16(&header[2]);
  const int header_analog = d.u16(&header[4]);
  info_.first_frame = d.u16(&header[6]);
  const int header_last = d.u16(&header[8]);
  info_.scale = d.f32(&header[12]);
  const int header_data_start = d.u16(&header[16]);
  const int header_analog_per_frame = d.u16(&header[18]);
  const double header_rate = d.f32(&header[20]);

  parse_parameters(parameter_header[2], header_data_start);
  const Parameter* point_used = parameter("POINT", "USED");
  const Parameter* analog_used = parameter("ANALOG", "USED");

  // Scale: the header wins (MACsample's header is right, its parameter wrong).
  if (const Parameter* scale = parameter("POINT", "SCALE"); scale && !scale->numbers.empty()) {
    const double parameter_scale = scale->numbers[0];
    if (!(info_.scale == 0.0) && std::isfinite(info_.scale)) {
      if (std::abs(parameter_scale - info_.scale) > 1e-6 * std::abs(info_.scale))
        warn("header scale " + detail::format_number(info_.scale) + " != POINT:SCALE " +
             detail::format_number(parameter_scale));
    } else if (std::isfinite(parameter_scale)) {
      info_.scale = parameter_scale;
    }
  }
  if (!std::isfinite(info_.scale)) {
    warn("the scale factor is not a finite number; assuming float storage");
    info_.scale = -1.0;
  }
  info_.format = info_.scale < 0.0 ? StorageFormat::floating : StorageFormat::integer;

  // Data start: header word 9, POINT:DATA_START when the header one is unusable (Dance has 0
  // in the parameter, so the header is the usual truth).
  int data_start = header_data_start;
  if (const Parameter* p = parameter("POINT", "DATA_START"); p && !p->words.empty()) {
    const int parameter_start = p->words[0];
    if (parameter_start != header_data_start)
      warn("header data_start " + std::to_string(header_data_start) + " != POINT:DATA_START " +
           std::to_string(parameter_start));
    if (header_data_start <= parameter_block && parameter_start > parameter_block)
      data_start = parameter_start;
  }
  if (data_start <= parameter_block)
    throw C3dError(name_, 16,
                   "the data section start (block " + std::to_string(data_start) +
                       ") is not after the parameter section (block " + std::to_string(parameter_block) +
                       ")");
  info_.data_offset = std::int64_t(data_start - 1) * 512;
  if (info_.data_offset > size_)
    throw C3dError(name_, 16,
                   "the data section should start in block " + std::to_string(data_start) + " at byte " +
                       std::to_string(info_.data_offset) + ", but the file has only " +
                       std::to_string(size_) + " bytes");

  // Rate: POINT:RATE, else the header (Xsens and BTS files lack the parameter). A rate that is
  // not a positive number, or none a camera runs at, is said: it makes every time in the outputs wrong.
  info_.rate = header_rate;
  const auto positive = [](double rate) { return rate > 0.0 && std::isfinite(rate); };
  if (const Parameter* p = parameter("POINT", "RATE"); p && !p->numbers.empty()) {
    if (positive(p->numbers[0]))
      info_.rate = p->numbers[0];
    else if (positive(header_rate))
      warn("POINT:RATE is " + detail::format_number(p->numbers[0]) + "; the header's " +
           detail::format_number(header_rate) + " Hz is used");
  }
  if (!positive(info_.rate)) {
    warn("no valid frame rate: the header says " + detail::format_number(header_rate) +
         " Hz and POINT:RATE gives none that is a positive number");
    info_.rate = 0.0;
  } else if (!plausible_frame_rate(info_.rate)) {
    warn("the frame rate " + detail::format_number(info_.rate) +
         " Hz is implausible (motion capture runs at " + detail::format_number(kPlausibleFrameRateHz[0]) +
         " to " + detail::format_number(kPlausibleFrameRateHz[1]) + " Hz)");
  }

  read_units();
  const std::int64_t declared = declared_frames(info_.first_frame, header_last);
  info_.declared_frame_count = declared;
  choose_layout(header_points, header_analog, header_analog_per_frame, point_used, analog_used, declared);
  read_labels();
  // One whole frame (points and analog) per read: a seek per frame costs more than the bytes.
  if (info_.frame_count > 0) buffer_.resize(static_cast<std::size_t>(info_.frame_bytes));
}

S2KF_INLINE void C3dReader::read_processor(std::uint8_t byte) {
  switch (byte) {
    case 84:
      info_.processor = Processor::intel;
      return;
    case 85:
      info_.processor = Processor::dec;
      return;
    case 86:
      info_.processor = Processor::mips;
      return;
    case 1:
    case 2:
    case 3:
      info_.processor = static_cast<Processor>(byte - 1);
      warn("processor type byte " + std::to_string(byte) + " instead of " + std::to_string(83 + byte));
      return;
    default:
      throw C3dError(name_, parameter_offset_ + 3,
                     "unknown processor type byte " + std::to_string(byte) + " at byte " +
                         std::to_string(parameter_offset_ + 3) + " (expected 84 Intel, 85 DEC or 86 MIPS)");
  }
}

S2KF_INLINE void C3dReader::parse_parameters(int declared_blocks, int header_data_start) {
  // The section is parsed from a bounded window: entry sizes come from the file, so every
  // length is checked against what was actually read before anything is allocated.
  constexpr std::int64_t max_window = std::int64_t(1) << 22;
  const std::int64_t window = std::min(size_ - parameter_offset_, max_window);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(window));
  read_at(parameter_offset_, bytes.data(), window);
  const detail::Decoder d(info_.processor);
  const int parameter_block = static_cast<int>(parameter_offset_ / 512) + 1;
  // Offsets may not point into the data section; entries themselves may run into it (sample18).
  std::int64_t soft_limit = window;
  if (header_data_start > parameter_block)
    soft_limit = std::min<std::int64_t>(window, std::int64_t(header_data_start - parameter_block) * 512);

  std::map<int, std::string> group_names;
  struct Pending {
    int group_id;
    Parameter parameter;
  };
  std::vector<Pending> pending;
  std::int64_t pos = 4;
  std::int64_t furthest = 4;
  const auto stop = [&](const std::string& why) {
    warn("parameter section: " + why + " at byte " + std::to_string(parameter_offset_ + pos) +
         "; the remaining parameters are ignored");
  };
  while (pos + 2 <= window) {
    const int name_length_signed = static_cast<std::int8_t>(bytes[pos]);
    if (name_length_signed == 0) break;
    const int id = static_cast<std::int8_t>(bytes[pos + 1]);
    const int name_length = std::abs(name_length_signed);
    if (id == 0) {
      stop("an entry with group id 0");
      break;
    }
    std::int64_t q = pos + 2;
    if (q + name_length + 2 > window) {
      stop("an entry cut off by the end of the file");
      break;
    }
    std::string name = upper_case(utf8_from_file_text(trim(
        std::string_view(reinterpret_cast<const char*>(&bytes[q]), static_cast<std::size_t>(name_length)))));
    q += name_length;
    const std::int64_t offset_position = q;
    const int offset = d.i16(&bytes[q]);
    q += 2;
    Parameter parameter;
    parameter.name = name;
    parameter.locked = name_length_signed < 0;
    std::int64_t structural_end = 0;  // end of the required fields, before the description
    if (id < 0) {
      structural_end = q;
    } else {
      if (q + 2 > window) {
        stop("a parameter cut off by the end of the file");
        break;
      }
      parameter.type = static_cast<std::int8_t>(bytes[q]);
      const int dimension_count = bytes[q + 1];
      q += 2;
      if (parameter.type != -1 && parameter.type != 1 && parameter.type != 2 && parameter.type != 4) {
        stop("parameter " + name + " of unknown type " + std::to_string(parameter.type));
        break;
      }
      if (dimension_count > 7 || q + dimension_count > window) {
        stop("parameter " + name + " with " + std::to_string(dimension_count) + " dimensions");
        break;
      }
      std::int64_t elements = 1;
      for (int i = 0; i < dimension_count; ++i) {
        parameter.dimensions.push_back(bytes[q + i]);
        elements *= bytes[q + i];  // at most 255^7 < 2^63
      }
      q += dimension_count;
      const std::int64_t data_bytes = elements * std::abs(parameter.type);
      if (data_bytes > window - q) {
        stop("parameter " + name + " whose " + std::to_string(data_bytes) + " data bytes run past the file");
        break;
      }
      decode_values(parameter, &bytes[q], elements, d);
      q += data_bytes;
      structural_end = q;
    }
    // Description: an unsigned length (BKIN has 0xA3), which may be cut off without harm.
    std::int64_t natural_end = structural_end;
    if (structural_end < window) {
      const int description_length = bytes[structural_end];
      const std::int64_t available = std::min<std::int64_t>(description_length, window - structural_end - 1);
      parameter.description = utf8_from_file_text(trim(std::string_view(
          reinterpret_cast<const char*>(&bytes[structural_end + 1]), static_cast<std::size_t>(available))));
      natural_end = structural_end + 1 + available;
    }
    if (id < 0) {
      group_names.emplace(-id, name);  // the first group with an id names it
    } else {
      pending.push_back({id, std::move(parameter)});
    }
    furthest = std::max(furthest, natural_end);
    if (offset == 0) break;  // the writer marked this entry the last one
    std::int64_t next = offset_position + offset;
    if (next < structural_end || next > soft_limit) {
      warn("bad offset-to-next " + std::to_string(offset) + " at " + name + " (points to " +
           std::to_string(parameter_offset_ + next) + ", limit " +
           std::to_string(parameter_offset_ + soft_limit) + "); using computed end " +
           std::to_string(parameter_offset_ + natural_end));
      next = natural_end;
    }
    if (next <= pos) break;  // cannot happen (natural_end > pos), kept as a guard against loops
    if (next >= soft_limit) break;
    pos = next;
  }
  if (declared_blocks > 0 && furthest > std::int64_t(declared_blocks) * 512)
    warn("parameters extend beyond declared " + std::to_string(declared_blocks) + " blocks");

  // Parameters may precede their group, so names are resolved only now.
  std::set<std::pair<std::string, std::string>> seen;
  std::vector<std::string> repeated;
  int orphans = 0;
  for (Pending& p : pending) {
    const auto group = group_names.find(p.group_id);
    if (group == group_names.end()) {
      ++orphans;
      continue;
    }
    p.parameter.group = group->second;
    if (!seen.insert({p.parameter.group, p.parameter.name}).second)
      repeated.push_back(p.parameter.group + ":" + p.parameter.name);
    parameters_.push_back(std::move(p.parameter));
  }
  if (orphans > 0) warn(std::to_string(orphans) + " parameters belong to no group and are ignored");
  if (!repeated.empty())
    warn(std::to_string(repeated.size()) + " repeated parameters, the first of each is used (" +
         repeated.front() + (repeated.size() > 1 ? ", ...)" : ")"));
}

S2KF_INLINE void C3dReader::read_units() {
  const Parameter* units = parameter("POINT", "UNITS");
  if (!units || units->strings.empty()) {
    warn("no POINT:UNITS; assuming mm");
    return;
  }
  info_.units = units->strings[0];
  const std::string u = lower_case(info_.units);
  if (u == "mm" || u == "millimeters" || u == "millimetres" || u == "millimeter" || u == "millimetre")
    info_.to_mm = 1.0;
  else if (u == "m" || u == "meters" || u == "metres" || u == "meter" || u == "metre")
    info_.to_mm = 1000.0;
  else if (u == "cm" || u == "centimeters" || u == "centimetres")
    info_.to_mm = 10.0;
  else if (u == "dm")
    info_.to_mm = 100.0;
  else if (u == "in" || u == "inch" || u == "inches")
    info_.to_mm = 25.4;
  else
    warn("unknown POINT:UNITS \"" + info_.units + "\"; assuming mm");
}

S2KF_INLINE std::int64_t C3dReader::declared_frames(int header_first, int header_last) {
  const std::int64_t header_count =
      header_last >= header_first ? std::int64_t(header_last) - std::max(header_first, 1) + 1 : 0;
  std::int64_t frames = 0;
  if (!unsigned_value(parameter("POINT", "FRAMES"), frames)) {
    if (header_last == 65535) return -1;
    return header_count;
  }
  if (frames != 65535) {
    if (frames != header_count && header_last != 65535)
      warn("POINT:FRAMES " + std::to_string(frames) + " != header frames " + std::to_string(header_count));
    return frames;
  }
  std::int64_t long_frames = 0;
  if (unsigned_value(parameter("POINT", "LONG_FRAMES"), long_frames) && long_frames >= 65535)
    return long_frames;
  const Parameter* start = parameter("TRIAL", "ACTUAL_START_FIELD");
  const Parameter* end = parameter("TRIAL", "ACTUAL_END_FIELD");
  if (start && end && start->words.size() >= 2 && end->words.size() >= 2) {
    const std::int64_t first = std::int64_t(start->words[0]) | (std::int64_t(start->words[1]) << 16);
    const std::int64_t last = std::int64_t(end->words[0]) | (std::int64_t(end->words[1]) << 16);
    if (last >= first) return last - first + 1;
  }
  return -1;
}

S2KF_INLINE std::vector<std::string> C3dReader::collect_strings(const std::string& base) const {
  // LABELS, LABELS2, LABELS3, ... form one list.
  std::vector<std::string> all;
  for (int k = 1; k < 1000; ++k) {
    const Parameter* p = parameter("POINT", k == 1 ? base : base + std::to_string(k));
    if (!p) break;
    all.insert(all.end(), p->strings.begin(), p->strings.end());
  }
  return all;
}

S2KF_INLINE void C3dReader::read_labels() {
  const int points = info_.point_count;
  std::vector<std::string> raw = collect_strings("LABELS");
  std::vector<std::string> descriptions = collect_strings("DESCRIPTIONS");
  if (!raw.empty() && static_cast<int>(raw.size()) < points)
    warn("POINT:LABELS has " + std::to_string(raw.size()) + " labels for " + std::to_string(points) +
         " points");
  raw.resize(static_cast<std::size_t>(points));
  descriptions.resize(static_cast<std::size_t>(points));
  info_.descriptions = descriptions;

  std::set<std::string> model_outputs;
  for (const char* kind : {"ANGLES", "FORCES", "MOMENTS", "POWERS", "SCALARS", "REACTIONS"})
    if (const Parameter* p = parameter("POINT", kind))
      for (const std::string& s : p->strings)
        if (!s.empty()) model_outputs.insert(s);

  // Motion Analysis truncates labels to 4 characters; when that makes them repeat and the
  // descriptions are unique, the descriptions are the real names (Walk1).
  const std::set<std::string> distinct_raw(raw.begin(), raw.end());
  const std::set<std::string> distinct_descriptions(descriptions.begin(), descriptions.end());
  const bool use_descriptions = points > 0 && static_cast<int>(distinct_raw.size()) < points &&
                                static_cast<int>(distinct_descriptions.size()) == points &&
                                distinct_descriptions.count("") == 0;
  if (use_descriptions) warn("POINT:LABELS repeat; point names are taken from POINT:DESCRIPTIONS");

  info_.labels.resize(static_cast<std::size_t>(points));
  std::set<std::pair<std::string, std::string>> taken;
  int empty = 0;
  std::vector<std::string> renamed;
  for (int i = 0; i < points; ++i) {
    PointLabel& label = info_.labels[static_cast<std::size_t>(i)];
    label.raw = raw[static_cast<std::size_t>(i)];
    label.model_output = model_outputs.count(label.raw) > 0;
    std::string name = use_descriptions ? descriptions[static_cast<std::size_t>(i)] : label.raw;
    if (!use_descriptions) {
      const std::size_t colon = name.rfind(':');
      if (colon != std::string::npos) {
        label.subject = name.substr(0, colon);
        name = name.substr(colon + 1);
        label.model_output = label.model_output || model_outputs.count(name) > 0;
      }
    }
    if (name.empty()) {
      name = "point_" + std::to_string(i + 1);
      ++empty;
    }
    if (!taken.insert({label.subject, name}).second) {
      std::string unique;
      for (int k = 2;; ++k) {
        unique = name + "_" + std::to_string(k);
        if (taken.insert({label.subject, unique}).second) break;
      }
      renamed.push_back(name + " -> " + unique);
      name = unique;
    }
    label.name = name;
  }
  zero_is_missing_.resize(info_.labels.size());
  for (std::size_t i = 0; i < info_.labels.size(); ++i)
    zero_is_missing_[i] = info_.labels[i].model_output ? 0 : 1;
  if (empty > 0) warn(std::to_string(empty) + " points have no label and are named point_<number>");
  if (!renamed.empty()) {
    std::string list;
    for (std::size_t k = 0; k < renamed.size() && k < 8; ++k) list += (k ? ", " : "") + renamed[k];
    if (renamed.size() > 8) list += ", ...";
    warn(std::to_string(renamed.size()) + " duplicate labels renamed (" + list + ")");
  }
}

S2KF_INLINE void C3dReader::read_at(std::int64_t offset, std::uint8_t* data, std::int64_t count) {
  stream_->clear();
  stream_->seekg(offset);
  stream_->read(reinterpret_cast<char*>(data), count);
  if (stream_->gcount() != count)
    throw C3dError(name_, offset + stream_->gcount(),
                   "the file ends at byte " + std::to_string(offset + stream_->gcount()) + " while reading " +
                       std::to_string(count) + " bytes from byte " + std::to_string(offset));
}

S2KF_INLINE void C3dReader::load_next(double* xyz, bool* visible) {
  const std::int64_t index = next_frame_;
  const std::int64_t offset = info_.data_offset + index * info_.frame_bytes;
  if (!positioned_) {
    stream_->clear();
    stream_->seekg(offset);
    positioned_ = true;
  }
  stream_->read(reinterpret_cast<char*>(buffer_.data()), info_.frame_bytes);
  if (!*stream_) {
    positioned_ = false;
    throw C3dError(name_, offset,
                   "the file ends inside frame " + std::to_string(index) + " of " +
                       std::to_string(info_.frame_count) + " (was it changed while being read?)");
  }
  decode_points(buffer_.data(), xyz, visible);
  ++next_frame_;
}

S2KF_INLINE void C3dReader::decode_points(const std::uint8_t* data, double* xyz, bool* visible) const {
  const int points = info_.point_count;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double to_mm = info_.to_mm;
  const auto store = [&](int p, bool missing, double x, double y, double z) {
    missing =
        missing || detail::sentinel_coordinates(x, y, z, zero_is_missing_[static_cast<std::size_t>(p)] != 0);
    visible[p] = !missing;
    if (missing) {
      xyz[3 * p] = xyz[3 * p + 1] = xyz[3 * p + 2] = nan;
    } else {
      xyz[3 * p] = x * to_mm;
      xyz[3 * p + 1] = y * to_mm;
      xyz[3 * p + 2] = z * to_mm;
    }
  };
  if (info_.format == StorageFormat::floating) {
    if (info_.processor == Processor::intel) {
      // The common case without per-word byte shuffling.
      for (int p = 0; p < points; ++p) {
        float w[4];
        std::memcpy(w, data + 16 * p, 16);
        store(p, detail::float_residual_missing(w[3]), w[0], w[1], w[2]);
      }
    } else {
      const detail::Decoder d(info_.processor);
      for (int p = 0; p < points; ++p) {
        const std::uint8_t* q = data + 16 * p;
        store(p, detail::float_residual_missing(d.f32(q + 12)), d.f32(q), d.f32(q + 4), d.f32(q + 8));
      }
    }
  } else {
    const detail::Decoder d(info_.processor);
    const double scale = info_.scale;
    for (int p = 0; p < points; ++p) {
      const std::uint8_t* q = data + 8 * p;
      store(p, d.i16(q + 6) < 0, d.i16(q) * scale, d.i16(q + 2) * scale, d.i16(q + 4) * scale);
    }
  }
}

S2KF_INLINE Recording read_all(C3dReader& reader) {
  Recording recording;
  recording.info = reader.info();
  recording.labels = marker_labels(recording.info);
  recording.rate_hz = recording.info.rate;
  reader.read_frames(reader.info().frame_count - reader.next_frame(), recording.positions, recording.visible);
  return recording;
}

S2KF_INLINE Recording read_c3d(const std::string& path) {
  C3dReader reader(path);
  return read_all(reader);
}

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::c3d
