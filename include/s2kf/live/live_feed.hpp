/// @file
/// A QTM stream received on a thread of its own, for a consumer that may be slower than the stream:
/// frames wait in a bounded backlog (the oldest give way to the newest, counted), markers keep the
/// order of the labels of the first connection (a label list that changes is re-mapped, and which
/// labels came and went is said), and a lost connection is re-established with back-off.
#pragma once

#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/live/qtm_client.hpp>
#include <s2kf/live/qtm_protocol.hpp>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace s2kf::live {

struct FeedOptions {
  std::size_t backlog = 16;       ///< frames kept while the consumer is busy (at least 1)
  double connect_timeout_s = 5;   ///< for each connection attempt
  double reconnect_seconds = 10;  ///< after a lost connection, give up after this long
  /// Lines about the connection (lost, re-established, labels changed); called on the receiving
  /// thread.
  std::function<void(const std::string&)> log;
};

/// One received frame, markers in the order of LiveFeed::parameters().labels.
struct LiveFrame {
  std::uint32_t number = 0;  ///< the server's frame number
  std::chrono::steady_clock::time_point arrival;
  Eigen::Matrix3Xd positions;
  FrameVisibility visible;
};

struct FeedCounts {
  long received = 0;                       ///< frames received
  long dropped = 0;                        ///< frames given up because the backlog was full
  long reconnects = 0;                     ///< connections re-established
  std::vector<std::string> label_changes;  ///< one sentence per change of the label list
};

class LiveFeed {
 public:
  /// Connects, reads the parameters and starts streaming; a ConnectionError or ProtocolError
  /// when that fails.
  LiveFeed(std::string host, std::uint16_t port, FeedOptions options)
      : host_(std::move(host)), port_(port), options_(std::move(options)) {
    options_.backlog = std::max<std::size_t>(1, options_.backlog);
    limit_ = options_.backlog;
    client_ = std::make_unique<QtmClient>(host_, port_, options_.connect_timeout_s);
    parameters_ = client_->parameters();
    current_labels_ = parameters_.labels;
    update_mapping();
    client_->stream_frames();
    thread_ = std::thread([this] { receive(); });
  }
  ~LiveFeed() { stop(); }
  LiveFeed(const LiveFeed&) = delete;
  LiveFeed& operator=(const LiveFeed&) = delete;

  /// The labels (of the first connection) and the frequency.
  const StreamParameters& parameters() const { return parameters_; }

  /// The oldest frame kept, waiting up to `timeout_ms` (-1: until one comes or the stream ends).
  /// Returns `frame`, `timeout`, or `ended` (ended_reason() says why, failed() whether in error).
  enum class Next { frame, timeout, ended };
  Next next(LiveFrame& out, int timeout_ms) {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto ready = [&] { return !backlog_.empty() || ended_; };
    if (timeout_ms < 0)
      arrived_.wait(lock, ready);
    else if (!arrived_.wait_for(lock, std::chrono::milliseconds(timeout_ms), ready))
      return Next::timeout;
    if (backlog_.empty()) return Next::ended;
    out = std::move(backlog_.front());
    backlog_.pop_front();
    // Catching up: the allowance shrinks with each frame taken, so that a consumer slower than the
    // stream comes back to the backlog's bound; once caught up, the bound is the backlog again.
    if (limit_ > options_.backlog) --limit_;
    if (backlog_.empty()) limit_ = options_.backlog;
    return Next::frame;
  }

  /// Keeps up to `frames` (not only the backlog) until the consumer has caught up, i.e. emptied
  /// the backlog: after a held first stretch the consumer is that far behind by design, and
  /// frames dropped then would be lost for nothing. The allowance shrinks by one with each frame
  /// taken, so a consumer that never catches up is back to the backlog after `frames` frames.
  void keep_until_caught_up(std::size_t frames) {
    std::lock_guard<std::mutex> lock(mutex_);
    limit_ = std::max(options_.backlog, frames);
  }

  /// True from keep_until_caught_up until the consumer has emptied the backlog (or used up the
  /// allowance): the frames it takes meanwhile were waiting behind the held stretch.
  bool catching_up() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return limit_ > options_.backlog;
  }

  /// Ends the stream (says "Bye" to the server) and the receiving thread.
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    if (thread_.joinable()) thread_.join();
    if (client_) client_->bye();
    client_.reset();
  }

  bool failed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return failed_;
  }
  std::string ended_reason() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return ended_reason_;
  }
  FeedCounts counts() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return counts_;
  }

 private:
  bool stopping() {
    std::lock_guard<std::mutex> lock(mutex_);
    return stopping_;
  }

  void end(const std::string& reason, bool failed) {
    std::lock_guard<std::mutex> lock(mutex_);
    ended_ = true;
    failed_ = failed;
    ended_reason_ = reason;
    arrived_.notify_all();
  }

  void say(const std::string& line) {
    if (options_.log) options_.log(line);
  }

  /// source_of_[k]: the column of the current labels that holds label k of the first connection.
  void update_mapping() {
    source_of_.assign(parameters_.labels.size(), -1);
    for (std::size_t k = 0; k < parameters_.labels.size(); ++k) {
      const auto found = std::find(current_labels_.begin(), current_labels_.end(), parameters_.labels[k]);
      if (found != current_labels_.end()) source_of_[k] = static_cast<int>(found - current_labels_.begin());
    }
  }

  /// After the server announced a change, or a frame's marker count disagrees with the labels.
  void refresh_labels() {
    std::vector<std::string> previous = current_labels_;
    const StreamParameters now = client_->parameters();
    if (now.rate_hz != parameters_.rate_hz)
      throw ProtocolError("the frequency changed from " + std::to_string(parameters_.rate_hz) + " to " +
                          std::to_string(now.rate_hz) + " Hz during the stream");
    current_labels_ = now.labels;
    if (current_labels_ == previous) return;
    update_mapping();
    std::string went, came;
    for (const std::string& label : previous)
      if (std::find(current_labels_.begin(), current_labels_.end(), label) == current_labels_.end())
        went += (went.empty() ? "" : ", ") + label;
    for (const std::string& label : current_labels_)
      if (std::find(previous.begin(), previous.end(), label) == previous.end())
        came += (came.empty() ? "" : ", ") + label;
    const std::string change =
        went.empty() && came.empty()
            ? std::string("the label list changed its order; markers re-mapped by label")
            : "the label list changed (" + std::to_string(previous.size()) + " -> " +
                  std::to_string(current_labels_.size()) +
                  " labels; went: " + (went.empty() ? "none" : went) +
                  "; came: " + (came.empty() ? "none" : came) + "); markers re-mapped by label";
    say(change);
    std::lock_guard<std::mutex> lock(mutex_);
    counts_.label_changes.push_back(change);
  }

  void push(const Frame3d& frame, std::chrono::steady_clock::time_point arrival) {
    LiveFrame out;
    out.number = frame.frame_number;
    out.arrival = arrival;
    const auto markers = static_cast<Eigen::Index>(parameters_.labels.size());
    out.positions.setConstant(3, markers, std::numeric_limits<double>::quiet_NaN());
    out.visible.setConstant(markers, false);
    for (Eigen::Index k = 0; k < markers; ++k) {
      const int from = source_of_[static_cast<std::size_t>(k)];
      if (from < 0 || from >= frame.positions.cols()) continue;
      out.positions.col(k) = frame.positions.col(from);
      out.visible(k) = frame.visible(from);
    }
    std::lock_guard<std::mutex> lock(mutex_);
    ++counts_.received;
    if (backlog_.size() >= limit_) {
      backlog_.pop_front();
      ++counts_.dropped;
    }
    backlog_.push_back(std::move(out));
    arrived_.notify_one();
  }

  /// Connects again with back-off (0.1 s doubling to 2 s) until reconnect_seconds have passed.
  bool reconnect(const std::string& why) {
    client_.reset();
    const auto give_up =
        std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                               std::chrono::duration<double>(options_.reconnect_seconds));
    double wait_s = 0.1;
    say("connection lost (" + why + "); reconnecting to " + host_ + ":" + std::to_string(port_));
    while (!stopping()) {
      try {
        auto client = std::make_unique<QtmClient>(host_, port_, options_.connect_timeout_s);
        client_ = std::move(client);
        refresh_labels();
        client_->stream_frames();
        std::lock_guard<std::mutex> lock(mutex_);
        ++counts_.reconnects;
        say("reconnected");
        return true;
      } catch (const ConnectionError&) {
        client_.reset();
      }
      if (std::chrono::steady_clock::now() >= give_up) return false;
      std::this_thread::sleep_for(std::chrono::duration<double>(wait_s));
      wait_s = std::min(2.0, 2 * wait_s);
    }
    return false;
  }

  void receive() {
    Frame3d frame;
    Event event{};
    try {
      while (!stopping()) {
        QtmClient::Item item;
        try {
          item = client_->next(frame, event, 100);
        } catch (const ConnectionError& e) {
          if (!reconnect(e.what()))
            return end("the connection was lost and could not be re-established", true);
          continue;
        }
        switch (item) {
          case QtmClient::Item::frame:
            if (static_cast<std::size_t>(frame.positions.cols()) != current_labels_.size()) refresh_labels();
            if (static_cast<std::size_t>(frame.positions.cols()) != current_labels_.size())
              throw ProtocolError("frame " + std::to_string(frame.frame_number) + " has " +
                                  std::to_string(frame.positions.cols()) +
                                  " markers but the parameters list " +
                                  std::to_string(current_labels_.size()) + " labels");
            push(frame, std::chrono::steady_clock::now());
            break;
          case QtmClient::Item::no_more_data:
            return end("the server has no more data", false);
          case QtmClient::Item::event:
            if (event == Event::camera_settings_changed || event == Event::rt_from_file_started)
              refresh_labels();
            if (event == Event::qtm_shutting_down) return end("the server is shutting down", false);
            break;
          case QtmClient::Item::closed:
            if (!reconnect("the server closed it"))
              return end("the connection was lost and could not be re-established", true);
            break;
          case QtmClient::Item::timeout:
            break;
        }
      }
      end("stopped", false);
    } catch (const ProtocolError& e) {
      if (client_) client_->socket().close();
      end(std::string("malformed stream, connection closed: ") + e.what(), true);
    } catch (const std::exception& e) {
      if (client_) client_->socket().close();
      end(e.what(), true);
    }
  }

  std::string host_;
  std::uint16_t port_;
  FeedOptions options_;
  std::unique_ptr<QtmClient> client_;
  StreamParameters parameters_;
  std::vector<std::string> current_labels_;
  std::vector<int> source_of_;
  std::thread thread_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::deque<LiveFrame> backlog_;
  std::size_t limit_ = 1;  ///< the backlog's bound now: options_.backlog, more while catching up
  bool stopping_ = false;
  bool ended_ = false;
  bool failed_ = false;
  std::string ended_reason_;
  FeedCounts counts_;
};

}  // namespace s2kf::live
