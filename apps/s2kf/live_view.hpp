/// @file
/// `s2kf live --view`: a local web server (cpp-httplib) that serves the viewer page and follows the
/// stream by server-sent events. Each browser gets the newest frame when it can take one; frames
/// published meanwhile are skipped for it (counted), so a slow browser never makes anything queue.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

namespace s2kf::cli {

class LiveView {
 public:
  /// Serves on address:port (port 0: one the system chooses); a UserError when it cannot.
  LiveView(const std::string& address, int port, const std::string& page);
  /// Ends every browser's stream and stops the server.
  ~LiveView();
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  /// The address to open, http://ADDRESS:PORT/.
  std::string url() const;
  /// The page's metadata (JSON), sent first to each browser; frames wait for it.
  void set_metadata(std::string json);
  /// True while at least one browser follows the stream (else a frame need not be made).
  bool watched() const;
  /// The newest frame's record (base64), replacing the one before.
  void publish(std::string record);
  /// Tells every browser that the stream ended (why) and stops sending.
  void finish(const std::string& why);

  struct Counts {
    long browsers = 0;  ///< event streams opened
    long sent = 0;      ///< frames sent, over all browsers
    long skipped = 0;   ///< frames a browser did not get because a newer one came first
  };
  Counts counts() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace s2kf::cli
