/// @file
/// Datagrams to one UDP address (POSIX): each tracked frame goes out as one message, never waiting;
/// a message the system cannot take at once is dropped and counted (a live output must not slow
/// the tracker).
#pragma once

#include <s2kf/live/packet_channel.hpp>

#include <netdb.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>

namespace s2kf::live {

class UdpSender {
 public:
  /// A ConnectionError when the host cannot be resolved.
  UdpSender(const std::string& host, std::uint16_t port) {
    const AddressList found = resolve(host, port, SOCK_DGRAM, "send to");
    socket_ = open_socket(*found);
    if (!socket_.open() || ::connect(socket_.fd(), found->ai_addr, found->ai_addrlen) != 0)
      throw ConnectionError("cannot send to " + detail::address_text(host, port) + ": " +
                            std::strerror(errno));
  }

  /// Sends one datagram; false (and counted) when it could not go out at once.
  bool send(const void* bytes, std::size_t count) {
    if (::send(socket_.fd(), bytes, count, MSG_DONTWAIT | MSG_NOSIGNAL) == static_cast<ssize_t>(count)) {
      ++sent_;
      return true;
    }
    ++dropped_;
    return false;
  }
  bool send(const std::string& text) { return send(text.data(), text.size()); }

  long sent() const { return sent_; }
  long dropped() const { return dropped_; }

 private:
  Socket socket_;
  long sent_ = 0;
  long dropped_ = 0;
};

}  // namespace s2kf::live
