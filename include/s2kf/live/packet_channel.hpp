/// @file
/// QTM protocol packets over a TCP connection (POSIX sockets): connecting, listening, reading whole
/// packets with time limits into one reused buffer of at most kMaxPacketBytes, and sending them.
#pragma once

#include <s2kf/live/qtm_protocol.hpp>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::live {

/// The peer cannot be reached (no such host, refused, timed out) or the connection failed: one
/// sentence.
struct ConnectionError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A socket descriptor closed with its owner.
class Socket {
 public:
  Socket() = default;
  explicit Socket(int fd) : fd_(fd) {}
  Socket(Socket&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  Socket& operator=(Socket&& other) noexcept {
    if (this != &other) {
      close();
      fd_ = std::exchange(other.fd_, -1);
    }
    return *this;
  }
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;
  ~Socket() { close(); }
  int fd() const { return fd_; }
  bool open() const { return fd_ >= 0; }
  void close() {
    if (fd_ >= 0) ::close(std::exchange(fd_, -1));
  }
  /// Ends both directions at once (a reader blocked on it in another thread wakes up).
  void shutdown() {
    if (fd_ >= 0) ::shutdown(fd_, SHUT_RDWR);
  }

 private:
  int fd_ = -1;
};

namespace detail {
/// True when `fd` becomes readable (or has an error or end) within `timeout_ms` (-1: no limit).
inline bool wait_readable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  for (;;) {
    const int ready = ::poll(&p, 1, timeout_ms);
    if (ready >= 0) return ready > 0;
    if (errno != EINTR)
      throw ConnectionError(std::string("waiting for data failed: ") + std::strerror(errno));
  }
}

inline std::string address_text(const std::string& host, std::uint16_t port) {
  return (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" + std::to_string(port);
}
}  // namespace detail

/// getaddrinfo's list of addresses, freed with its owner.
using AddressList = std::unique_ptr<addrinfo, decltype(&::freeaddrinfo)>;

/// The addresses of host:port for sockets of `socktype` (SOCK_STREAM, SOCK_DGRAM); `passive` for a
/// socket to listen on. A ConnectionError "cannot DOING HOST:PORT: why" when the name does not
/// resolve (`doing`: "connect to", "listen on", "send to").
inline AddressList resolve(const std::string& host, std::uint16_t port, int socktype,
                           const std::string& doing, bool passive = false) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = socktype;
  hints.ai_flags = passive ? AI_PASSIVE : 0;
  addrinfo* found = nullptr;
  const int status = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found);
  if (status != 0)
    throw ConnectionError("cannot " + doing + " " + detail::address_text(host, port) + ": " +
                          ::gai_strerror(status));
  return AddressList(found, &::freeaddrinfo);
}

/// A socket for `address` (closed on exec: a child process does not inherit it); not open when the
/// system refuses (errno says why).
inline Socket open_socket(const addrinfo& address) {
  return Socket(::socket(address.ai_family, address.ai_socktype | SOCK_CLOEXEC, address.ai_protocol));
}

/// A TCP connection to host:port within `timeout_s`, with Nagle's delay off (a frame goes out at
/// once). A ConnectionError says why not, e.g. "cannot connect to 127.0.0.1:22223: Connection
/// refused".
inline Socket connect_tcp(const std::string& host, std::uint16_t port, double timeout_s) {
  const std::string where = detail::address_text(host, port);
  const AddressList found = resolve(host, port, SOCK_STREAM, "connect to");
  std::string problem = "no address";
  Socket connected;
  for (const addrinfo* a = found.get(); a && !connected.open(); a = a->ai_next) {
    Socket s = open_socket(*a);
    if (!s.open()) {
      problem = std::strerror(errno);
      continue;
    }
    const int flags = ::fcntl(s.fd(), F_GETFL, 0);
    ::fcntl(s.fd(), F_SETFL, flags | O_NONBLOCK);
    if (::connect(s.fd(), a->ai_addr, a->ai_addrlen) != 0) {
      if (errno != EINPROGRESS) {
        problem = std::strerror(errno);
        continue;
      }
      pollfd p{s.fd(), POLLOUT, 0};
      const int ready = ::poll(&p, 1, static_cast<int>(timeout_s * 1000));
      if (ready <= 0) {
        problem = ready == 0 ? "no answer within " + std::to_string(static_cast<int>(timeout_s)) + " s"
                             : std::strerror(errno);
        continue;
      }
      int error = 0;
      socklen_t length = sizeof error;
      ::getsockopt(s.fd(), SOL_SOCKET, SO_ERROR, &error, &length);
      if (error != 0) {
        problem = std::strerror(error);
        continue;
      }
    }
    ::fcntl(s.fd(), F_SETFL, flags);
    const int one = 1;
    ::setsockopt(s.fd(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    connected = std::move(s);
  }
  if (!connected.open()) throw ConnectionError("cannot connect to " + where + ": " + problem);
  return connected;
}

/// A listening TCP socket on address:port (port 0: one the system chooses); `bound_port` gets the
/// port.
inline Socket listen_tcp(const std::string& address, std::uint16_t port, std::uint16_t& bound_port) {
  const std::string where = detail::address_text(address, port);
  const AddressList found = resolve(address, port, SOCK_STREAM, "listen on", true);
  Socket s = open_socket(*found);
  const int one = 1;
  std::string problem;
  if (!s.open())
    problem = std::strerror(errno);
  else if (::setsockopt(s.fd(), SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
           ::bind(s.fd(), found->ai_addr, found->ai_addrlen) != 0 || ::listen(s.fd(), 4) != 0)
    problem = std::strerror(errno);
  if (!problem.empty()) throw ConnectionError("cannot listen on " + where + ": " + problem);
  sockaddr_storage bound{};
  socklen_t length = sizeof bound;
  ::getsockname(s.fd(), reinterpret_cast<sockaddr*>(&bound), &length);
  bound_port = ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&bound)->sin6_port
                                                 : reinterpret_cast<sockaddr_in*>(&bound)->sin_port);
  return s;
}

/// Whole packets over a connected socket. One packet's body is kept in a buffer reused for the
/// next, never larger than kMaxPacketBytes.
class PacketChannel {
 public:
  /// What read() found.
  enum class Read { packet, timeout, closed };
  /// Once a packet has begun, the rest must arrive within this long.
  static constexpr int kRestOfPacketMs = 2000;

  PacketChannel() = default;
  explicit PacketChannel(Socket socket) : socket_(std::move(socket)) {}

  Socket& socket() { return socket_; }
  bool open() const { return socket_.open(); }

  /// Waits up to `timeout_ms` (-1: no limit) for a packet: `packet` when one arrived (header() and
  /// body() describe it), `timeout`, or `closed` when the peer ended the connection between
  /// packets. A ProtocolError for a malformed header or a connection that ends or stalls inside a
  /// packet; a ConnectionError when the socket fails.
  Read read(int timeout_ms) {
    if (!detail::wait_readable(socket_.fd(), timeout_ms)) return Read::timeout;
    std::uint8_t header[kHeaderBytes];
    const std::size_t got = receive(header, kHeaderBytes, true);
    if (got == 0) return Read::closed;
    if (got < kHeaderBytes) parse_header(header, got);  // throws: truncated header
    header_ = parse_header(header, kHeaderBytes);
    body_.resize(header_.body_bytes());
    const std::size_t body_got = receive(body_.data(), body_.size(), false);
    if (body_got < body_.size())
      throw ProtocolError("truncated packet: " + std::to_string(kHeaderBytes + body_got) + " of its " +
                          std::to_string(header_.size) + " declared bytes arrived");
    return Read::packet;
  }

  const PacketHeader& header() const { return header_; }
  const std::vector<std::uint8_t>& body() const { return body_; }
  std::string text() const { return packet_text(body_.data(), body_.size()); }

  /// Sends a whole packet; a ConnectionError when the peer is gone.
  void send(const std::vector<std::uint8_t>& packet) {
    std::size_t sent = 0;
    while (sent < packet.size()) {
      const ssize_t n = ::send(socket_.fd(), packet.data() + sent, packet.size() - sent, MSG_NOSIGNAL);
      if (n < 0) {
        if (errno == EINTR) continue;
        throw ConnectionError(std::string("sending failed: ") + std::strerror(errno));
      }
      sent += static_cast<std::size_t>(n);
    }
  }

 private:
  /// Up to `count` bytes; fewer only when the connection ends (or, past the first byte, stalls for
  /// kRestOfPacketMs). 0 at once when the peer closed before the first byte and `at_boundary`.
  std::size_t receive(std::uint8_t* into, std::size_t count, bool at_boundary) {
    std::size_t got = 0;
    while (got < count) {
      if ((got > 0 || !at_boundary) && !detail::wait_readable(socket_.fd(), kRestOfPacketMs)) return got;
      const ssize_t n = ::recv(socket_.fd(), into + got, count - got, 0);
      if (n == 0) return got;
      if (n < 0) {
        if (errno == EINTR) continue;
        if (errno == ECONNRESET && got == 0 && at_boundary) return 0;
        throw ConnectionError(std::string("receiving failed: ") + std::strerror(errno));
      }
      got += static_cast<std::size_t>(n);
    }
    return got;
  }

  Socket socket_;
  PacketHeader header_;
  std::vector<std::uint8_t> body_;
};

}  // namespace s2kf::live
