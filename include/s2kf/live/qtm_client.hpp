/// @file
/// A client of the QTM real-time protocol: connect (welcome, "Version 1.25"), ask for the General
/// and 3D parameters, stream every frame's 3D component, and say "Bye".
#pragma once

#include <s2kf/live/packet_channel.hpp>
#include <s2kf/live/qtm_protocol.hpp>

#include <cstdint>
#include <deque>
#include <string>

namespace s2kf::live {

class QtmClient {
 public:
  /// What next() found.
  enum class Item { frame, no_more_data, event, timeout, closed };

  /// Connects to host:port and sets the protocol version. A ConnectionError when the server
  /// cannot be reached, a ProtocolError when it does not speak the protocol.
  QtmClient(const std::string& host, std::uint16_t port, double timeout_s = 5)
      : channel_(connect_tcp(host, port, timeout_s)) {
    const int timeout_ms = static_cast<int>(timeout_s * 1000);
    const PacketChannel::Read welcome = channel_.read(timeout_ms);
    // Closed before the welcome: a server going away (its last queued connection), not a malformed one.
    if (welcome == PacketChannel::Read::closed)
      throw ConnectionError("the server at " + host + ":" + std::to_string(port) +
                            " closed the connection before its welcome");
    if (welcome != PacketChannel::Read::packet)
      throw ProtocolError("the server at " + host + ":" + std::to_string(port) + " sent no welcome");
    if (channel_.header().type == PacketType::error)
      throw ProtocolError("the server refused the connection: " + channel_.text());
    if (channel_.header().type != PacketType::command || channel_.text().rfind(kWelcome, 0) != 0)
      throw ProtocolError("the server at " + host + ":" + std::to_string(port) +
                          " does not speak the QTM real-time protocol (no \"" + std::string(kWelcome) +
                          "\")");
    const std::string version = std::to_string(kProtocolMajor) + "." + std::to_string(kProtocolMinor);
    const std::string answer = command("Version " + version, timeout_ms);
    if (answer != "Version set to " + version)
      throw ProtocolError("the server did not accept protocol version " + version + " (it answered \"" +
                          answer + "\")");
  }

  /// The labels and frequency ("GetParameters General 3D").
  StreamParameters parameters(int timeout_ms = 5000) {
    channel_.send(text_packet(PacketType::command, "GetParameters General 3D"));
    for (;;) {
      const PacketChannel::Read read = channel_.read(timeout_ms);
      if (read == PacketChannel::Read::timeout) throw ProtocolError("the server sent no parameters in time");
      if (read == PacketChannel::Read::closed) throw ConnectionError("the server closed the connection");
      if (channel_.header().type == PacketType::error)
        throw ProtocolError("the server refused GetParameters: " + channel_.text());
      if (channel_.header().type == PacketType::xml) return parse_parameters_xml(channel_.text());
      if (channel_.header().type == PacketType::data) {
        // Frames streamed while the answer was on its way are kept for next() (the newest few).
        if (waiting_.size() == kMaxWaitingFrames) waiting_.pop_front();
        waiting_.emplace_back();
        parse_data_body(channel_.body().data(), channel_.body().size(), waiting_.back());
      }
    }
  }

  /// Starts the stream of every frame's 3D component ("StreamFrames AllFrames 3D"); no answer.
  void stream_frames() { channel_.send(text_packet(PacketType::command, "StreamFrames AllFrames 3D")); }

  /// The next packet of the stream within `timeout_ms`: a frame (into `frame`), the end of the
  /// data, an event (into `event`), nothing in time, or the end of the connection. Commands'
  /// answers are passed over; an error packet is a ProtocolError with its text.
  Item next(Frame3d& frame, Event& event, int timeout_ms) {
    if (!waiting_.empty()) {
      frame = std::move(waiting_.front());
      waiting_.pop_front();
      if (!frame.has_3d)
        throw ProtocolError("data packet " + std::to_string(frame.frame_number) + " has no 3D component");
      return Item::frame;
    }
    for (;;) {
      const PacketChannel::Read read = channel_.read(timeout_ms);
      if (read == PacketChannel::Read::timeout) return Item::timeout;
      if (read == PacketChannel::Read::closed) return Item::closed;
      const std::vector<std::uint8_t>& body = channel_.body();
      switch (channel_.header().type) {
        case PacketType::data:
          parse_data_body(body.data(), body.size(), frame);
          if (!frame.has_3d)
            throw ProtocolError("data packet " + std::to_string(frame.frame_number) + " has no 3D component");
          return Item::frame;
        case PacketType::no_more_data:
          return Item::no_more_data;
        case PacketType::event:
          if (body.size() != 1)
            throw ProtocolError("an event packet of " + std::to_string(body.size() + kHeaderBytes) +
                                " bytes (an event is one byte)");
          event = static_cast<Event>(body[0]);
          return Item::event;
        case PacketType::error:
          throw ProtocolError("the server reports an error: " + channel_.text());
        default:
          break;  // answers to commands, files: not for the stream
      }
    }
  }

  /// Stops the stream and says goodbye; the connection is closed.
  void bye() {
    try {
      channel_.send(text_packet(PacketType::command, "StreamFrames Stop"));
      channel_.send(text_packet(PacketType::command, "Bye"));
    } catch (const ConnectionError&) {
    }
    channel_.socket().close();
  }

  Socket& socket() { return channel_.socket(); }

 private:
  /// Sends a command and returns the text of the command packet that answers it.
  std::string command(const std::string& text, int timeout_ms) {
    channel_.send(text_packet(PacketType::command, text));
    for (;;) {
      const PacketChannel::Read read = channel_.read(timeout_ms);
      if (read == PacketChannel::Read::timeout) throw ProtocolError("no answer to \"" + text + "\" in time");
      if (read == PacketChannel::Read::closed) throw ConnectionError("the server closed the connection");
      if (channel_.header().type == PacketType::error)
        throw ProtocolError("the server refused \"" + text + "\": " + channel_.text());
      if (channel_.header().type == PacketType::command) return channel_.text();
    }
  }

  static constexpr std::size_t kMaxWaitingFrames = 256;
  PacketChannel channel_;
  std::deque<Frame3d> waiting_;
};

}  // namespace s2kf::live
