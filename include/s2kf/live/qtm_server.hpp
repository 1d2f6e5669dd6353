/// @file
/// A server of the QTM real-time protocol that streams a recording's frames at a rate, as QTM
/// streams a capture: one client at a time, commands "Version", "GetParameters", "StreamFrames",
/// "GetCurrentFrame", "Bye". The playback clock starts at the first "StreamFrames" and runs on
/// while no client listens (a client that reconnects misses the frames in between). For tests, it
/// can also misbehave on purpose (ServeFaults).
#pragma once

#include <s2kf/io/frame_source.hpp>
#include <s2kf/live/packet_channel.hpp>
#include <s2kf/live/qtm_protocol.hpp>

#include <poll.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace s2kf::live {

/// Deliberate faults, each after a number of frames sent (-1: never).
struct ServeFaults {
  long disconnect_after = -1;  ///< close the client's connection once
  long relabel_after = -1;     ///< swap the first two labels, announce it with an event (once)
  long skip_every = 0;         ///< leave out every n-th frame number (0: none)
  long malformed_after = -1;   ///< send a data packet whose size lies, then close
  long unlabel_after = -1;     ///< stop sending the last label and its marker, unannounced (once)
};

struct ServeOptions {
  std::string address = "127.0.0.1";
  std::uint16_t port = kDefaultPort;  ///< 0: one the system chooses
  double rate_hz = 0;                 ///< 0: the recording's rate
  bool loop = false;                  ///< start again at the end instead of sending the end of data
  ServeFaults faults;
};

class QtmServer {
 public:
  /// Listens at once (a ConnectionError when it cannot); `source` must outlive the server.
  QtmServer(FrameSource& source, ServeOptions options)
      : source_(source),
        options_(std::move(options)),
        listener_(listen_tcp(options_.address, options_.port, port_)) {
    if (source_.frame_count() <= 0) throw std::invalid_argument("the recording holds no frame to serve");
    rate_ = options_.rate_hz > 0 ? options_.rate_hz : source_.rate_hz();
    if (!(rate_ > 0) || !std::isfinite(rate_)) throw std::invalid_argument("no valid frame rate to serve at");
    labels_ = source_.labels();
  }

  std::uint16_t port() const { return port_; }
  double rate_hz() const { return rate_; }
  /// Frames sent so far, over all connections.
  long frames_sent() const { return frames_sent_; }

  /// Serves until `stop` is set, or (without loop) the recording has been streamed to its end and
  /// the client has left. `log` receives one line per connection event.
  void run(const std::atomic<bool>& stop, const std::function<void(const std::string&)>& log = {}) {
    const auto say = [&](const std::string& line) {
      if (log) log(line);
    };
    while (!stop.load()) {
      if (finished_ && !client_.open()) return;
      int wait_ms = 100;
      if (streaming_ && client_.open() && !finished_) {
        const double due =
            std::chrono::duration<double>(next_due() - std::chrono::steady_clock::now()).count();
        wait_ms = std::max(0, std::min(100, static_cast<int>(std::ceil(due * 1000))));
      }
      pollfd fds[2] = {{listener_.fd(), POLLIN, 0}, {client_.open() ? client_.socket().fd() : -1, POLLIN, 0}};
      if (::poll(fds, 2, wait_ms) < 0 && errno != EINTR)
        throw ConnectionError(std::string("waiting for clients failed: ") + std::strerror(errno));
      if (fds[0].revents & POLLIN) accept_client(say);
      try {
        if (client_.open() && (fds[1].revents & (POLLIN | POLLHUP | POLLERR))) serve_command(say);
        if (client_.open() && streaming_ && !finished_) send_due_frames(say);
      } catch (const std::exception& e) {
        say(std::string("client left: ") + e.what());
        client_ = PacketChannel();
        streaming_ = false;
      }
    }
  }

 private:
  using Clock = std::chrono::steady_clock;

  Clock::time_point next_due() const {
    return start_ + std::chrono::duration_cast<Clock::duration>(
                        std::chrono::duration<double>(static_cast<double>(next_frame_) / rate_));
  }

  void accept_client(const std::function<void(const std::string&)>& say) {
    Socket incoming(::accept4(listener_.fd(), nullptr, nullptr, SOCK_CLOEXEC));
    if (!incoming.open()) return;
    const int one = 1;
    ::setsockopt(incoming.fd(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    PacketChannel channel(std::move(incoming));
    try {
      if (client_.open()) {
        channel.send(text_packet(PacketType::error, "another client is connected; one at a time"));
        return;
      }
      channel.send(text_packet(PacketType::command, kWelcome));
    } catch (const ConnectionError&) {
      return;
    }
    client_ = std::move(channel);
    say("client connected");
  }

  void serve_command(const std::function<void(const std::string&)>& say) {
    const PacketChannel::Read read = client_.read(0);
    if (read == PacketChannel::Read::timeout) return;
    if (read == PacketChannel::Read::closed) {
      say("client disconnected");
      client_ = PacketChannel();
      streaming_ = false;
      return;
    }
    if (client_.header().type != PacketType::command) {
      client_.send(text_packet(PacketType::error, "only command packets are understood"));
      return;
    }
    std::istringstream words(client_.text());
    std::string verb;
    words >> verb;
    if (verb == "Version") {
      std::string version;
      words >> version;
      int major = 0, minor = 0;
      char dot = 0;
      std::istringstream v(version);
      if (v >> major >> dot >> minor && dot == '.' && major == 1 && minor >= 8)
        client_.send(text_packet(PacketType::command, "Version set to " + version));
      else
        client_.send(
            text_packet(PacketType::error, "version " + version + " is not served (1.8 and later are)"));
    } else if (verb == "GetParameters") {
      StreamParameters parameters{labels_, rate_};
      client_.send(text_packet(PacketType::xml, parameters_xml(parameters)));
    } else if (verb == "StreamFrames") {
      std::string argument;
      bool stop = false, with_3d = false;
      while (words >> argument) {
        stop = stop || argument == "Stop";
        with_3d = with_3d || argument == "3D";
      }
      if (stop) {
        streaming_ = false;
      } else if (!with_3d) {
        client_.send(text_packet(PacketType::error, "only the 3D component is served"));
      } else {
        if (!clock_started_) {
          start_ = Clock::now();
          clock_started_ = true;
        }
        streaming_ = true;
        // Frames due while no client streamed are passed over, as a camera system's would be.
        const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
        next_frame_ = std::max(next_frame_, static_cast<long>(std::floor(elapsed * rate_)));
      }
    } else if (verb == "GetCurrentFrame") {
      if (finished_ || !clock_started_)
        client_.send(no_more_data_packet());
      else
        send_frame(std::max(0L, next_frame_ - 1));
    } else if (verb == "Bye") {
      say("client said bye");
      client_ = PacketChannel();
      streaming_ = false;
    } else {
      client_.send(text_packet(PacketType::error, "unknown command \"" + verb + "\""));
    }
  }

  void send_frame(long played) {
    const long frames = static_cast<long>(source_.frame_count());
    const long index = played % frames;
    if (!source_.read(index, frame_))
      throw std::runtime_error("frame " + std::to_string(index) + " cannot be read");
    if (relabelled_ && frame_.positions.cols() >= 2) {
      frame_.positions.col(0).swap(frame_.positions.col(1));
      const bool first = frame_.visible(0);
      frame_.visible(0) = frame_.visible(1);
      frame_.visible(1) = first;
    }
    if (frame_.positions.cols() > static_cast<Eigen::Index>(labels_.size())) {
      frame_.positions.conservativeResize(Eigen::NoChange, static_cast<Eigen::Index>(labels_.size()));
      frame_.visible.conservativeResize(static_cast<Eigen::Index>(labels_.size()));
    }
    const auto timestamp =
        static_cast<std::uint64_t>(std::llround(static_cast<double>(played) / rate_ * 1e6));
    client_.send(
        data_packet_3d(static_cast<std::uint32_t>(played + 1), timestamp, frame_.positions, frame_.visible));
  }

  void send_due_frames(const std::function<void(const std::string&)>& say) {
    const long frames = static_cast<long>(source_.frame_count());
    const ServeFaults& faults = options_.faults;
    while (client_.open() && streaming_ && Clock::now() >= next_due()) {
      if (!options_.loop && next_frame_ >= frames) {
        client_.send(no_more_data_packet());
        finished_ = true;
        say("end of the recording");
        return;
      }
      const long played = next_frame_++;
      if (faults.skip_every > 0 && (played + 1) % faults.skip_every == 0) continue;
      if (faults.malformed_after >= 0 && frames_sent_ == faults.malformed_after) {
        std::vector<std::uint8_t> lie =
            data_packet_3d(static_cast<std::uint32_t>(played + 1), 0, frame_.positions, frame_.visible);
        detail::set_u32(lie, 0, static_cast<std::uint32_t>(kMaxPacketBytes + 1));
        client_.send(lie);
        say("sent a malformed packet (a fault asked for)");
        client_ = PacketChannel();
        streaming_ = false;
        return;
      }
      send_frame(played);
      ++frames_sent_;
      if (faults.disconnect_after >= 0 && frames_sent_ == faults.disconnect_after && !disconnected_) {
        disconnected_ = true;
        say("closed the connection (a fault asked for)");
        client_ = PacketChannel();
        streaming_ = false;
        return;
      }
      if (faults.unlabel_after >= 0 && frames_sent_ == faults.unlabel_after && !unlabelled_ &&
          !labels_.empty()) {
        unlabelled_ = true;
        labels_.pop_back();
      }
      if (faults.relabel_after >= 0 && frames_sent_ == faults.relabel_after && !relabelled_ &&
          labels_.size() >= 2) {
        relabelled_ = true;
        std::swap(labels_[0], labels_[1]);
        client_.send(event_packet(Event::camera_settings_changed));
      }
    }
  }

  FrameSource& source_;
  ServeOptions options_;
  std::uint16_t port_ = 0;
  Socket listener_;
  double rate_ = 0;
  std::vector<std::string> labels_;
  PacketChannel client_;
  bool streaming_ = false;
  bool clock_started_ = false;
  bool finished_ = false;
  bool disconnected_ = false;
  bool relabelled_ = false;
  bool unlabelled_ = false;
  Clock::time_point start_;
  long next_frame_ = 0;
  long frames_sent_ = 0;
  MarkerFrame frame_;
};

}  // namespace s2kf::live
