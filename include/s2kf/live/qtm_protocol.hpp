/// @file
/// The subset of the Qualisys Track Manager (QTM) real-time protocol, version 1.25, that carries
/// labelled 3D markers over TCP: packet headers, the commands as text, the XML of the General and
/// 3D parameters (frequency, labels), the 3D component of data packets, events and the end of data.
/// Parsing and writing only, no sockets: every length is checked against the bytes at hand and a
/// fixed bound, so a packet that lies about its size is an error, never a crash or a big allocation.
/// docs/live.md lists the facts and where they come from.
#pragma once

#include <s2kf/io/marker_sequence.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace s2kf::live {

/// A packet, an XML text or a command that does not follow the protocol: one sentence.
struct ProtocolError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The protocol version both sides of s2kf speak ("Version 1.25").
constexpr int kProtocolMajor = 1;
constexpr int kProtocolMinor = 25;
/// QTM's little-endian port (its base port 22222 + 1); the base port speaks only version 1.0.
constexpr std::uint16_t kDefaultPort = 22223;
/// Every packet starts with its size (header included) and its type, 32-bit little-endian each.
constexpr std::size_t kHeaderBytes = 8;
/// The largest packet accepted: 3D data for 80,000 markers, or a parameter XML of a megabyte.
constexpr std::size_t kMaxPacketBytes = std::size_t{1} << 20;
/// The welcome a server sends as a command packet when a client connects.
constexpr std::string_view kWelcome = "QTM RT Interface connected";

enum class PacketType : std::uint32_t {
  error = 0,
  command = 1,
  xml = 2,
  data = 3,
  no_more_data = 4,
  c3d_file = 5,
  event = 6,
  discover = 7,
  qtm_file = 8,
};
constexpr std::uint32_t kPacketTypeCount = 9;  // types 0..8; 9 ("none") is never sent

/// Event packets carry one byte; these are the ones s2kf acts on or sends.
enum class Event : std::uint8_t {
  connected = 1,
  connection_closed = 2,
  capture_started = 3,
  capture_stopped = 4,
  camera_settings_changed = 11,
  rt_from_file_started = 8,
  rt_from_file_stopped = 9,
  qtm_shutting_down = 12,
};

/// Data component types; s2kf reads type 1 (3D, labelled) and skips the others by their size.
constexpr std::uint32_t kComponent3d = 1;

struct PacketHeader {
  std::uint32_t size = 0;  ///< bytes of the whole packet, header included
  PacketType type = PacketType::error;
  std::size_t body_bytes() const { return size - kHeaderBytes; }
};

namespace detail {
inline std::uint32_t get_u32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
         std::uint32_t{p[3]} << 24;
}
inline std::uint16_t get_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(std::uint16_t{p[0]} | std::uint16_t{p[1]} << 8);
}
inline std::uint64_t get_u64(const std::uint8_t* p) {
  return std::uint64_t{get_u32(p)} | std::uint64_t{get_u32(p + 4)} << 32;
}
inline float get_f32(const std::uint8_t* p) {
  const std::uint32_t bits = get_u32(p);
  float value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}
inline void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}
inline void put_u16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v));
  out.push_back(static_cast<std::uint8_t>(v >> 8));
}
inline void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
  put_u32(out, static_cast<std::uint32_t>(v));
  put_u32(out, static_cast<std::uint32_t>(v >> 32));
}
inline void put_f32(std::vector<std::uint8_t>& out, float value) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  put_u32(out, bits);
}
inline void set_u32(std::vector<std::uint8_t>& out, std::size_t at, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out[at + static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(v >> (8 * k));
}
}  // namespace detail

/// The header in the first 8 of `bytes`; a ProtocolError when fewer than 8 bytes are given, the
/// size is below 8 or above kMaxPacketBytes, or the type is not one of the protocol's.
inline PacketHeader parse_header(const std::uint8_t* bytes, std::size_t count) {
  if (count < kHeaderBytes)
    throw ProtocolError("truncated packet header: " + std::to_string(count) + " of its 8 bytes");
  PacketHeader header;
  header.size = detail::get_u32(bytes);
  const std::uint32_t type = detail::get_u32(bytes + 4);
  if (header.size < kHeaderBytes)
    throw ProtocolError("a packet declares " + std::to_string(header.size) +
                        " bytes, fewer than its own 8-byte header");
  if (header.size > kMaxPacketBytes)
    throw ProtocolError("a packet declares " + std::to_string(header.size) + " bytes, more than the " +
                        std::to_string(kMaxPacketBytes) + " accepted");
  if (type >= kPacketTypeCount) throw ProtocolError("unknown packet type " + std::to_string(type));
  header.type = static_cast<PacketType>(type);
  return header;
}

/// A packet of `type` with `body` after its header.
inline std::vector<std::uint8_t> make_packet(PacketType type, const std::uint8_t* body, std::size_t bytes) {
  if (bytes + kHeaderBytes > kMaxPacketBytes)
    throw ProtocolError("a packet of " + std::to_string(bytes + kHeaderBytes) + " bytes exceeds the " +
                        std::to_string(kMaxPacketBytes) + " a peer accepts");
  std::vector<std::uint8_t> out;
  out.reserve(kHeaderBytes + bytes);
  detail::put_u32(out, static_cast<std::uint32_t>(kHeaderBytes + bytes));
  detail::put_u32(out, static_cast<std::uint32_t>(type));
  out.insert(out.end(), body, body + bytes);
  return out;
}

/// Command, error and XML packets carry text ending in a NUL.
inline std::vector<std::uint8_t> text_packet(PacketType type, std::string_view text) {
  std::vector<std::uint8_t> body(text.begin(), text.end());
  body.push_back(0);
  return make_packet(type, body.data(), body.size());
}

/// The text of a command, error or XML body: up to its first NUL (the NUL is optional).
inline std::string packet_text(const std::uint8_t* body, std::size_t bytes) {
  const auto* begin = reinterpret_cast<const char*>(body);
  const void* nul = std::memchr(begin, 0, bytes);
  return std::string(begin, nul ? static_cast<const char*>(nul) : begin + bytes);
}

inline std::vector<std::uint8_t> event_packet(Event event) {
  const auto byte = static_cast<std::uint8_t>(event);
  return make_packet(PacketType::event, &byte, 1);
}

inline std::vector<std::uint8_t> no_more_data_packet() {
  return make_packet(PacketType::no_more_data, nullptr, 0);
}

/// One frame of a data packet's 3D component: positions in mm as sent (single precision), a NaN
/// coordinate marking a missing marker.
struct Frame3d {
  std::uint64_t timestamp_us = 0;
  std::uint32_t frame_number = 0;
  bool has_3d = false;  ///< false when the packet carried no 3D component
  Eigen::Matrix3Xd positions;
  FrameVisibility visible;
};

/// The body (after the 8-byte header) of a data packet with one 3D component: timestamp (u64, us),
/// frame number (u32), component count (u32); the component: size (u32, its 8-byte header
/// included), type 1, marker count (u32), 2D drop rate and out-of-sync rate (u16 each), then x, y, z
/// (f32) per marker.
inline std::vector<std::uint8_t> data_packet_3d(std::uint32_t frame_number, std::uint64_t timestamp_us,
                                                const Eigen::Matrix3Xd& positions,
                                                const FrameVisibility& visible) {
  std::vector<std::uint8_t> body;
  const auto markers = static_cast<std::size_t>(positions.cols());
  body.reserve(16 + 16 + 12 * markers);
  detail::put_u64(body, timestamp_us);
  detail::put_u32(body, frame_number);
  detail::put_u32(body, 1);
  detail::put_u32(body, static_cast<std::uint32_t>(16 + 12 * markers));
  detail::put_u32(body, kComponent3d);
  detail::put_u32(body, static_cast<std::uint32_t>(markers));
  detail::put_u16(body, 0);
  detail::put_u16(body, 0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (Eigen::Index p = 0; p < positions.cols(); ++p)
    for (int axis = 0; axis < 3; ++axis)
      detail::put_f32(body, visible(p) ? static_cast<float>(positions(axis, p)) : nan);
  return make_packet(PacketType::data, body.data(), body.size());
}

/// Reads a data packet's body into `frame`; components other than 3D are skipped. A ProtocolError
/// when a count or size does not fit in the bytes given.
inline void parse_data_body(const std::uint8_t* body, std::size_t bytes, Frame3d& frame) {
  if (bytes < 16)
    throw ProtocolError("a data packet of " + std::to_string(bytes + kHeaderBytes) +
                        " bytes is too short for its timestamp, frame number and component count");
  frame.timestamp_us = detail::get_u64(body);
  frame.frame_number = detail::get_u32(body + 8);
  const std::uint32_t components = detail::get_u32(body + 12);
  frame.has_3d = false;
  std::size_t at = 16;
  for (std::uint32_t c = 0; c < components; ++c) {
    if (bytes - at < 8)
      throw ProtocolError("data packet component " + std::to_string(c + 1) + " of " +
                          std::to_string(components) + " begins past the packet's end");
    const std::uint32_t size = detail::get_u32(body + at);
    const std::uint32_t type = detail::get_u32(body + at + 4);
    if (size < 8 || size > bytes - at)
      throw ProtocolError("data packet component " + std::to_string(c + 1) + " declares " +
                          std::to_string(size) + " bytes, but " + std::to_string(bytes - at) +
                          " remain in the packet");
    if (type == kComponent3d) {
      if (size < 16)
        throw ProtocolError("a 3D component of " + std::to_string(size) + " bytes has no marker count");
      const std::uint32_t markers = detail::get_u32(body + at + 8);
      if (markers > (size - 16) / 12)
        throw ProtocolError("a 3D component declares " + std::to_string(markers) + " markers, but its " +
                            std::to_string(size) + " bytes hold at most " + std::to_string((size - 16) / 12));
      frame.positions.resize(3, markers);
      frame.visible.resize(markers);
      const std::uint8_t* point = body + at + 16;
      for (std::uint32_t p = 0; p < markers; ++p, point += 12) {
        const auto col = static_cast<Eigen::Index>(p);
        for (int axis = 0; axis < 3; ++axis) frame.positions(axis, col) = detail::get_f32(point + 4 * axis);
        frame.visible(col) = frame.positions.col(col).allFinite();
        if (!frame.visible(col))
          frame.positions.col(col).setConstant(std::numeric_limits<double>::quiet_NaN());
      }
      frame.has_3d = true;
    }
    at += size;
  }
}

/// What a client needs of the parameters: the 3D labels in the order of the markers of a frame,
/// and the capture frequency.
struct StreamParameters {
  std::vector<std::string> labels;
  double rate_hz = 0;
};

namespace detail {

/// Element names and inner texts of the direct children of an XML fragment; comments, processing
/// instructions and attributes are skipped. A ProtocolError when tags do not nest.
struct XmlChild {
  std::string name;
  std::string_view inner;
};

inline std::vector<XmlChild> xml_children(std::string_view text) {
  std::vector<XmlChild> children;
  int depth = 0;
  std::size_t inner_start = 0;
  std::string open_name;
  std::size_t at = 0;
  while ((at = text.find('<', at)) != std::string_view::npos) {
    if (text.compare(at, 4, "<!--") == 0) {
      const std::size_t end = text.find("-->", at + 4);
      if (end == std::string_view::npos) throw ProtocolError("an XML comment is not closed");
      at = end + 3;
      continue;
    }
    const std::size_t close = text.find('>', at);
    if (close == std::string_view::npos) throw ProtocolError("an XML tag is not closed");
    const std::string_view tag = text.substr(at + 1, close - at - 1);
    const std::size_t tag_start = at;
    at = close + 1;
    if (tag.empty()) throw ProtocolError("an empty XML tag");
    if (tag.front() == '?' || tag.front() == '!') continue;
    const bool closing = tag.front() == '/';
    const bool self_closing = !closing && tag.back() == '/';
    std::string_view name = tag.substr(closing ? 1 : 0);
    name = name.substr(0, name.find_first_of(" \t\r\n/"));
    if (closing) {
      if (depth == 0)
        throw ProtocolError("the XML closes </" + std::string(name) + "> that was never opened");
      if (--depth == 0) {
        if (name != open_name)
          throw ProtocolError("the XML closes </" + std::string(name) + "> where <" + open_name +
                              "> is open");
        children.push_back({open_name, text.substr(inner_start, tag_start - inner_start)});
      }
    } else if (self_closing) {
      if (depth == 0) children.push_back({std::string(name), std::string_view()});
    } else {
      if (depth++ == 0) {
        open_name = std::string(name);
        inner_start = close + 1;
      }
    }
  }
  if (depth != 0) throw ProtocolError("the XML element <" + open_name + "> is not closed");
  return children;
}

inline std::string xml_unescape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '&') {
      out.push_back(text[i]);
      continue;
    }
    static const std::pair<std::string_view, char> entities[] = {
        {"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
    bool known = false;
    for (const auto& [entity, character] : entities)
      if (text.compare(i, entity.size(), entity) == 0) {
        out.push_back(character);
        i += entity.size() - 1;
        known = true;
        break;
      }
    if (!known) out.push_back('&');
  }
  const std::size_t first = out.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return std::string();
  return out.substr(first, out.find_last_not_of(" \t\r\n") - first + 1);
}

inline std::string xml_escape(std::string_view text) {
  std::string out;
  for (const char c : text) switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out.push_back(c);
    }
  return out;
}

}  // namespace detail

/// The labels and frequency from the XML answer to "GetParameters General 3D": the root element
/// holds <General><Frequency> and <The_3D> with <Labels> (the count) and one <Label><Name> per
/// marker. A ProtocolError names what is missing or inconsistent.
inline StreamParameters parse_parameters_xml(std::string_view xml) {
  const std::vector<detail::XmlChild> roots = detail::xml_children(xml);
  if (roots.size() != 1)
    throw ProtocolError("the parameters XML has " + std::to_string(roots.size()) + " root elements, not one");
  StreamParameters parameters;
  bool has_3d = false;
  for (const detail::XmlChild& section : detail::xml_children(roots.front().inner)) {
    if (section.name == "General") {
      for (const detail::XmlChild& item : detail::xml_children(section.inner))
        if (item.name == "Frequency") {
          const std::string text = detail::xml_unescape(item.inner);
          char* end = nullptr;
          parameters.rate_hz = std::strtod(text.c_str(), &end);
          if (text.empty() || *end != '\0' || !(parameters.rate_hz > 0) || !std::isfinite(parameters.rate_hz))
            throw ProtocolError("the parameters give the frequency \"" + text + "\", not a positive number");
        }
    } else if (section.name == "The_3D") {
      has_3d = true;
      long announced = -1;
      for (const detail::XmlChild& item : detail::xml_children(section.inner)) {
        if (item.name == "Labels") {
          const std::string text = detail::xml_unescape(item.inner);
          char* end = nullptr;
          announced = std::strtol(text.c_str(), &end, 10);
          if (text.empty() || *end != '\0' || announced < 0)
            throw ProtocolError("the 3D parameters give the label count \"" + text + "\"");
        } else if (item.name == "Label") {
          std::string name;
          for (const detail::XmlChild& field : detail::xml_children(item.inner))
            if (field.name == "Name") name = detail::xml_unescape(field.inner);
          parameters.labels.push_back(name);
        }
      }
      if (announced >= 0 && static_cast<std::size_t>(announced) != parameters.labels.size())
        throw ProtocolError("the 3D parameters announce " + std::to_string(announced) + " labels but list " +
                            std::to_string(parameters.labels.size()));
    }
  }
  if (!has_3d) throw ProtocolError("the parameters XML has no <The_3D> section (no 3D data is configured)");
  if (!(parameters.rate_hz > 0)) throw ProtocolError("the parameters XML gives no <General><Frequency>");
  return parameters;
}

/// The XML a server answers "GetParameters General 3D" with.
inline std::string parameters_xml(const StreamParameters& parameters) {
  std::string xml = "<QTM_Parameters_Ver_" + std::to_string(kProtocolMajor) + "." +
                    std::to_string(kProtocolMinor) + ">\n  <General>\n    <Frequency>";
  const double rate = parameters.rate_hz;
  xml += rate == std::floor(rate) ? std::to_string(static_cast<long long>(rate)) : std::to_string(rate);
  xml += "</Frequency>\n  </General>\n  <The_3D>\n    <AxisUpwards>+Z</AxisUpwards>\n    <Labels>" +
         std::to_string(parameters.labels.size()) + "</Labels>\n";
  for (const std::string& label : parameters.labels)
    xml += "    <Label>\n      <Name>" + detail::xml_escape(label) + "</Name>\n    </Label>\n";
  xml += "  </The_3D>\n</QTM_Parameters_Ver_" + std::to_string(kProtocolMajor) + "." +
         std::to_string(kProtocolMinor) + ">\n";
  return xml;
}

}  // namespace s2kf::live
