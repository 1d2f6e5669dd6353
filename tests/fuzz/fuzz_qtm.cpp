// libFuzzer target for the QTM real-time protocol parser: the input is read as a stream of
// packets, as a client reads a connection; any input must give a ProtocolError or consistent
// packets, never a crash, an endless loop or an allocation beyond the packet bound.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "s2kf/live/qtm_protocol.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace s2kf::live;
  std::size_t at = 0;
  Frame3d frame;
  try {
    while (at < size) {
      const PacketHeader header = parse_header(data + at, size - at);
      if (header.size > size - at) break;  // the rest has not arrived
      const std::uint8_t* body = data + at + kHeaderBytes;
      switch (header.type) {
        case PacketType::data:
          parse_data_body(body, header.body_bytes(), frame);
          if (frame.has_3d) {
            if (static_cast<std::size_t>(frame.positions.cols()) * 12 > header.body_bytes()) std::abort();
            for (Eigen::Index p = 0; p < frame.positions.cols(); ++p)
              if (frame.visible(p) != frame.positions.col(p).allFinite()) std::abort();
          }
          break;
        case PacketType::xml: {
          const StreamParameters parameters = parse_parameters_xml(packet_text(body, header.body_bytes()));
          if (!(parameters.rate_hz > 0) || parameters.labels.size() > header.body_bytes()) std::abort();
          break;
        }
        default:
          if (packet_text(body, header.body_bytes()).size() > header.body_bytes()) std::abort();
      }
      at += header.size;
    }
  } catch (const ProtocolError&) {
  }
  return 0;
}
