// The QTM client, server and live feed over loopback (ports chosen by the system): every frame
// arrives as served, and each fault (skipped numbers, a changed label list, a lost connection, a
// malformed packet, a refused connection, a slow consumer) is handled as documented.
#include <s2kf/live/live_feed.hpp>
#include <s2kf/live/live_frame_source.hpp>
#include <s2kf/live/qtm_client.hpp>
#include <s2kf/live/qtm_server.hpp>
#include <s2kf/live/udp_sender.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace s2kf;
using namespace s2kf::live;

/// Markers on a circle, marker p of frame f at (p, f, 1000 + p) mm; marker 2 missing in odd frames.
MarkerSequence numbered_frames(long frames, int markers = 5, double rate = 200) {
  MarkerSequence sequence;
  for (int p = 0; p < markers; ++p) sequence.labels.push_back("M" + std::to_string(p));
  sequence.rate_hz = rate;
  sequence.resize(frames);
  for (long f = 0; f < frames; ++f) {
    Eigen::Matrix3Xd positions(3, markers);
    FrameVisibility visible = FrameVisibility::Constant(markers, true);
    for (int p = 0; p < markers; ++p) positions.col(p) << p, static_cast<double>(f), 1000 + p;
    if (f % 2 == 1) {
      visible(2) = false;
      positions.col(2).setConstant(std::nan(""));
    }
    sequence.set_frame(f, positions, visible);
  }
  return sequence;
}

/// A server on a thread of its own, stopped with the test.
struct ServerThread {
  ServerThread(const MarkerSequence& sequence, ServeOptions options) : source(sequence) {
    options.port = 0;
    server = std::make_unique<QtmServer>(source, options);
    thread = std::thread([this] { server->run(stop); });
  }
  ~ServerThread() {
    stop = true;
    thread.join();
  }
  std::uint16_t port() const { return server->port(); }
  SequenceFrameSource source;
  std::unique_ptr<QtmServer> server;
  std::atomic<bool> stop{false};
  std::thread thread;
};

/// Waits until `feed` has received `frames` frames (the server's pace is the machine's: a fixed
/// sleep fails on a busy one), for at most 20 s.
void wait_until_received(const LiveFeed& feed, long frames) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (feed.counts().received < frames && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_EQ(feed.counts().received, frames);
}

/// Every frame the source gives, until it ends.
std::vector<MarkerFrame> read_all(LiveFrameSource& source) {
  std::vector<MarkerFrame> frames;
  MarkerFrame frame;
  while (source.read(static_cast<std::int64_t>(frames.size()), frame)) frames.push_back(frame);
  return frames;
}

FeedOptions quiet_feed(std::size_t backlog = 10000) {
  FeedOptions options;
  options.backlog = backlog;
  options.reconnect_seconds = 3;
  return options;
}

TEST(LiveFeed, EveryFrameArrivesAsServed) {
  const MarkerSequence sequence = numbered_frames(60);
  ServerThread server(sequence, {});
  LiveFeed feed("127.0.0.1", server.port(), quiet_feed());
  EXPECT_EQ(feed.parameters().labels, sequence.labels);
  EXPECT_EQ(feed.parameters().rate_hz, 200.0);
  LiveFrameSource source(feed, {});
  const std::vector<MarkerFrame> frames = read_all(source);
  ASSERT_EQ(frames.size(), 60u);
  for (long f = 0; f < 60; ++f) {
    EXPECT_EQ(frames[static_cast<std::size_t>(f)].index, f);
    EXPECT_EQ(frames[static_cast<std::size_t>(f)].positions(1, 4), static_cast<double>(f));
    EXPECT_EQ(frames[static_cast<std::size_t>(f)].visible(2), f % 2 == 0);
  }
  EXPECT_FALSE(feed.failed());
  EXPECT_EQ(feed.ended_reason(), "the server has no more data");
  EXPECT_EQ(feed.counts().received, 60);
  EXPECT_EQ(source.missing_frames(), 0);
}

TEST(LiveFeed, HeldFirstStretchComesFirst) {
  const MarkerSequence sequence = numbered_frames(30);
  ServerThread server(sequence, {});
  LiveFeed feed("127.0.0.1", server.port(), quiet_feed());
  LiveFrameSource source(feed, {});
  const MarkerSequence& first = source.hold_first(10);
  ASSERT_EQ(first.frame_count(), 10);
  const std::vector<MarkerFrame> frames = read_all(source);
  ASSERT_EQ(frames.size(), 30u);
  for (std::size_t f = 0; f < frames.size(); ++f)
    EXPECT_EQ(frames[f].positions(1, 0), static_cast<double>(f));
}

TEST(LiveFeed, SkippedFrameNumbersAreCountedAndFilled) {
  const MarkerSequence sequence = numbered_frames(40);
  ServeOptions options;
  options.faults.skip_every = 5;  // numbers 5, 10, ... 40 never sent
  ServerThread server(sequence, options);
  LiveFeed feed("127.0.0.1", server.port(), quiet_feed());
  LiveFrameSource source(feed, {});
  const std::vector<MarkerFrame> frames = read_all(source);
  // Number 40 is the last frame: the stream ends before a gap shows it missing.
  EXPECT_EQ(source.missing_frames(), 7);
  EXPECT_EQ(source.filled_frames(), 7);
  ASSERT_EQ(frames.size(), 39u);
  // Frame 4 (number 5) is a frame without markers; the others keep their place in time.
  EXPECT_FALSE(frames[4].visible.any());
  EXPECT_EQ(frames[5].positions(1, 0), 5.0);
}

TEST(LiveFeed, ChangedLabelListIsRemapped) {
  const MarkerSequence sequence = numbered_frames(40);
  ServeOptions options;
  options.faults.relabel_after = 10;  // M0 and M1 swap places in the list and in the frames
  ServerThread server(sequence, options);
  std::vector<std::string> log;
  FeedOptions feed_options = quiet_feed();
  LiveFeed feed("127.0.0.1", server.port(), feed_options);
  LiveFrameSource source(feed, {});
  const std::vector<MarkerFrame> frames = read_all(source);
  ASSERT_GE(frames.size(), 30u);
  for (const MarkerFrame& frame : frames)
    if (frame.visible(0)) {
      EXPECT_EQ(frame.positions(0, 0), 0.0);  // M0 stays in column 0 whatever the server's order
      EXPECT_EQ(frame.positions(0, 1), 1.0);
    }
  const FeedCounts counts = feed.counts();
  ASSERT_EQ(counts.label_changes.size(), 1u);
  EXPECT_EQ(counts.label_changes[0], "the label list changed its order; markers re-mapped by label");
}

TEST(LiveFeed, MarkerCountChangeRereadsTheLabels) {
  const MarkerSequence sequence = numbered_frames(40);
  ServeOptions options;
  options.faults.unlabel_after = 10;  // M4 goes, unannounced: frames carry 4 markers from then on
  ServerThread server(sequence, options);
  LiveFeed feed("127.0.0.1", server.port(), quiet_feed());
  LiveFrameSource source(feed, {});
  const std::vector<MarkerFrame> frames = read_all(source);
  ASSERT_EQ(frames.size(), 40u);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    ASSERT_EQ(frames[f].positions.cols(), 5);
    EXPECT_EQ(frames[f].visible(4), f < 10) << f;
    EXPECT_EQ(frames[f].positions(0, 3), 3.0);
  }
  const FeedCounts counts = feed.counts();
  ASSERT_EQ(counts.label_changes.size(), 1u);
  EXPECT_EQ(counts.label_changes[0],
            "the label list changed (5 -> 4 labels; went: M4; came: none); markers re-mapped by label");
}

TEST(LiveFeed, LostConnectionIsReestablished) {
  const MarkerSequence sequence = numbered_frames(800, 5, 400);
  ServeOptions options;
  options.faults.disconnect_after = 20;
  ServerThread server(sequence, options);
  LiveFeed feed("127.0.0.1", server.port(), quiet_feed());
  LiveFrameSource source(feed, {});
  const std::vector<MarkerFrame> frames = read_all(source);
  EXPECT_EQ(feed.counts().reconnects, 1);
  EXPECT_FALSE(feed.failed()) << feed.ended_reason();
  EXPECT_EQ(feed.ended_reason(), "the server has no more data");
  // The frames sent while reconnecting are missing, filled in (up to a second, 400 frames).
  EXPECT_GE(feed.counts().received, 20);
  EXPECT_EQ(static_cast<long>(frames.size()), feed.counts().received + source.filled_frames());
  EXPECT_EQ(source.filled_frames(), source.missing_frames());
  EXPECT_EQ(frames.back().positions(1, 0), static_cast<double>(frames.size() - 1));
}

TEST(LiveFeed, GivesUpWhenTheServerIsGone) {
  const MarkerSequence sequence = numbered_frames(400, 5, 400);
  ServeOptions looped;
  looped.loop = true;  // it never ends by itself, however slowly the test runs
  auto server = std::make_unique<ServerThread>(sequence, looped);
  FeedOptions options = quiet_feed();
  options.reconnect_seconds = 0.3;
  LiveFeed feed("127.0.0.1", server->port(), options);
  LiveFrame frame;
  ASSERT_EQ(feed.next(frame, 2000), LiveFeed::Next::frame);
  server.reset();  // gone, and its port refuses
  while (feed.next(frame, 5000) == LiveFeed::Next::frame) {
  }
  EXPECT_TRUE(feed.failed());
  EXPECT_EQ(feed.ended_reason(), "the connection was lost and could not be re-established");
}

TEST(LiveFeed, MalformedPacketClosesWithAClearError) {
  const MarkerSequence sequence = numbered_frames(40);
  ServeOptions options;
  options.faults.malformed_after = 5;
  ServerThread server(sequence, options);
  LiveFeed feed("127.0.0.1", server.port(), quiet_feed());
  LiveFrameSource source(feed, {});
  const std::vector<MarkerFrame> frames = read_all(source);
  EXPECT_EQ(frames.size(), 5u);
  EXPECT_TRUE(feed.failed());
  EXPECT_NE(feed.ended_reason().find("malformed stream, connection closed: a packet declares 1048577 bytes"),
            std::string::npos)
      << feed.ended_reason();
}

TEST(LiveFeed, RefusedConnectionIsOneSentence) {
  std::uint16_t port = 0;
  { Socket probe = listen_tcp("127.0.0.1", 0, port); }  // a port nobody listens on any more
  try {
    LiveFeed feed("127.0.0.1", port, quiet_feed());
    FAIL() << "connected";
  } catch (const ConnectionError& e) {
    EXPECT_EQ(std::string(e.what()),
              "cannot connect to 127.0.0.1:" + std::to_string(port) + ": Connection refused");
  }
}

TEST(LiveFeed, SlowConsumerKeepsTheNewestWithinTheBacklog) {
  const MarkerSequence sequence = numbered_frames(100, 5, 2000);
  ServerThread server(sequence, {});
  LiveFeed feed("127.0.0.1", server.port(), quiet_feed(3));
  ASSERT_NO_FATAL_FAILURE(wait_until_received(feed, 100));  // the whole recording, none taken yet
  std::vector<std::uint32_t> numbers;
  LiveFrame frame;
  while (feed.next(frame, 2000) == LiveFeed::Next::frame) numbers.push_back(frame.number);
  EXPECT_EQ(numbers, (std::vector<std::uint32_t>{98, 99, 100}));
  EXPECT_EQ(feed.counts().dropped, 97);
}

TEST(LiveFeed, FramesArrivingWhileTheHeldStretchIsTrackedAreKept) {
  // A consumer that holds 60 frames is 60 behind once it starts: the 40 that arrive meanwhile are
  // kept, though the backlog is 10 (enough for the consumer's hiccups while it holds them).
  const MarkerSequence sequence = numbered_frames(100, 5, 500);
  ServerThread server(sequence, {});
  LiveFeed feed("127.0.0.1", server.port(), quiet_feed(10));
  LiveFrameSource source(feed, {});
  ASSERT_EQ(source.hold_first(60).frame_count(), 60);
  EXPECT_TRUE(feed.catching_up());
  ASSERT_NO_FATAL_FAILURE(
      wait_until_received(feed, 100));  // the whole recording (at 500 Hz 0.2 s, longer on a busy machine)
  const std::vector<MarkerFrame> frames = read_all(source);
  EXPECT_FALSE(feed.catching_up());
  ASSERT_EQ(frames.size(), 100u);
  for (std::size_t f = 0; f < frames.size(); ++f)
    EXPECT_EQ(frames[f].positions(1, 0), static_cast<double>(f));
  EXPECT_EQ(feed.counts().dropped, 0);
}

TEST(LiveFeed, OnceCaughtUpOnlyTheBacklogIsKept) {
  const MarkerSequence sequence = numbered_frames(400, 5, 400);
  ServerThread server(sequence, {});
  LiveFeed feed("127.0.0.1", server.port(), quiet_feed(3));
  LiveFrameSource source(feed, {});
  ASSERT_EQ(source.hold_first(40).frame_count(), 40);
  MarkerFrame frame;
  for (std::int64_t f = 0; f < 60; ++f) ASSERT_TRUE(source.read(f, frame));  // live, caught up
  EXPECT_FALSE(feed.catching_up());
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // about 120 frames arrive
  for (std::int64_t f = 60; source.read(f, frame); ++f) {
  }
  EXPECT_GT(feed.counts().dropped, 50);
}

TEST(QtmServer, AnswersCommandsAsQtmDoes) {
  const MarkerSequence sequence = numbered_frames(10);
  ServerThread server(sequence, {});
  PacketChannel channel(connect_tcp("127.0.0.1", server.port(), 2));
  ASSERT_EQ(channel.read(2000), PacketChannel::Read::packet);
  EXPECT_EQ(channel.text(), "QTM RT Interface connected");
  channel.send(text_packet(PacketType::command, "Version 1.25"));
  ASSERT_EQ(channel.read(2000), PacketChannel::Read::packet);
  EXPECT_EQ(channel.text(), "Version set to 1.25");
  channel.send(text_packet(PacketType::command, "GetCurrentFrame 3D"));
  ASSERT_EQ(channel.read(2000), PacketChannel::Read::packet);
  EXPECT_EQ(channel.header().type, PacketType::no_more_data);  // nothing streamed yet
  channel.send(text_packet(PacketType::command, "Nonsense"));
  ASSERT_EQ(channel.read(2000), PacketChannel::Read::packet);
  EXPECT_EQ(channel.header().type, PacketType::error);
  // A second client is turned away while one is connected.
  PacketChannel second(connect_tcp("127.0.0.1", server.port(), 2));
  ASSERT_EQ(second.read(2000), PacketChannel::Read::packet);
  EXPECT_EQ(second.header().type, PacketType::error);
}

TEST(PacketChannel, TruncatedPacketIsAnError) {
  std::uint16_t port = 0;
  Socket listener = listen_tcp("127.0.0.1", 0, port);
  std::thread peer([&] {
    Socket client(::accept(listener.fd(), nullptr, nullptr));
    std::vector<std::uint8_t> packet = text_packet(PacketType::command, "QTM RT Interface connected");
    ::send(client.fd(), packet.data(), 12, MSG_NOSIGNAL);  // the header and 4 of 27 bytes, then gone
  });
  PacketChannel channel(connect_tcp("127.0.0.1", port, 2));
  peer.join();
  try {
    channel.read(2000);
    FAIL() << "no error";
  } catch (const ProtocolError& e) {
    EXPECT_EQ(std::string(e.what()), "truncated packet: 12 of its 35 declared bytes arrived");
  }
}

// One resolver serves the TCP client, the listener and the UDP sender: the same messages, and a
// datagram really arrives.
TEST(PacketChannel, AddressesResolveForEverySocketKind) {
  const AddressList stream = resolve("127.0.0.1", 22223, SOCK_STREAM, "connect to");
  ASSERT_NE(stream.get(), nullptr);
  EXPECT_EQ(stream->ai_family, AF_INET);
  EXPECT_EQ(stream->ai_socktype, SOCK_STREAM);
  EXPECT_EQ(ntohs(reinterpret_cast<const sockaddr_in*>(stream->ai_addr)->sin_port), 22223);
  EXPECT_EQ(resolve("::1", 9, SOCK_DGRAM, "send to")->ai_family, AF_INET6);
  try {
    UdpSender sender("no-such-host.invalid", 9);
    FAIL() << "no error";
  } catch (const ConnectionError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("cannot send to no-such-host.invalid:9: ", 0), 0u) << e.what();
  }
  try {
    std::uint16_t port = 0;
    listen_tcp("no-such-host.invalid", 0, port);
    FAIL() << "no error";
  } catch (const ConnectionError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("cannot listen on no-such-host.invalid:0: ", 0), 0u) << e.what();
  }

  Socket receiver(::socket(AF_INET, SOCK_DGRAM, 0));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(receiver.fd(), reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  socklen_t length = sizeof address;
  ::getsockname(receiver.fd(), reinterpret_cast<sockaddr*>(&address), &length);
  UdpSender sender("localhost", ntohs(address.sin_port));
  ASSERT_TRUE(sender.send(std::string("pose")));
  char got[16] = {};
  ASSERT_TRUE(live::detail::wait_readable(receiver.fd(), 2000));
  EXPECT_EQ(::recv(receiver.fd(), got, sizeof got, 0), 4);
  EXPECT_EQ(std::string(got), "pose");
}

}  // namespace
