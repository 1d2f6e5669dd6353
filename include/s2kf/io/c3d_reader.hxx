/// @file
/// The definitions of <s2kf/io/c3d_reader.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/io/c3d_reader.hpp>

namespace s2kf::c3d {

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

}  // namespace s2kf::c3d
