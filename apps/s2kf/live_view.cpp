// The live view's web server (live_view.hpp): GET / is the viewer page, GET /events the stream of
// server-sent events "meta" (the page's metadata, once), "frame" (the newest record) and "end".
#include "live_view.hpp"

#include <s2kf/app/user_error.hpp>

#include <httplib.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace s2kf::cli {

struct LiveView::Impl {
  httplib::Server server;
  std::thread thread;
  std::string address;
  int port = 0;

  mutable std::mutex mutex;
  std::condition_variable changed;
  std::string metadata;
  std::string record;  // the newest frame's
  long sequence = 0;   // of the newest frame; 0: none yet
  bool ended = false;
  std::string end_reason;
  int following = 0;  // browsers with an open event stream
  Counts counts;

  /// The next piece of one browser's stream (waits up to a second for something new; a comment
  /// line then keeps the connection alive). `last`: the sequence it got last; `stream_ended`: set
  /// when the piece is the end event.
  std::string next_event(long& last, bool& metadata_sent, bool& stream_ended) {
    std::unique_lock<std::mutex> lock(mutex);
    changed.wait_for(lock, std::chrono::seconds(1), [&] {
      return ended || (!metadata_sent && !metadata.empty()) || (metadata_sent && sequence > last);
    });
    std::string out;
    if (!metadata_sent && !metadata.empty()) {
      out += "event: meta\ndata: " + metadata + "\n\n";
      metadata_sent = true;
    }
    if (metadata_sent && sequence > last) {
      if (last > 0) counts.skipped += sequence - last - 1;  // frames before the browser came are not skipped
      out += "event: frame\ndata: " + record + "\n\n";
      last = sequence;
      ++counts.sent;
    } else if (ended) {
      out += "event: end\ndata: " + end_reason + "\n\n";
      stream_ended = true;
    }
    return out.empty() ? std::string(": waiting\n\n") : out;
  }
};

LiveView::LiveView(const std::string& address, int port, const std::string& page)
    : impl_(std::make_unique<Impl>()) {
  Impl& view = *impl_;
  view.address = address;
  view.server.Get("/", [page](const httplib::Request&, httplib::Response& response) {
    response.set_content(page, "text/html; charset=utf-8");
  });
  view.server.Get("/events", [&view](const httplib::Request&, httplib::Response& response) {
    {
      std::lock_guard<std::mutex> lock(view.mutex);
      ++view.following;
      ++view.counts.browsers;
    }
    response.set_header("Cache-Control", "no-cache");
    struct Progress {
      long last = 0;
      bool metadata_sent = false, ended = false;
    };
    auto progress = std::make_shared<Progress>();
    response.set_chunked_content_provider(
        "text/event-stream",
        [&view, progress](std::size_t, httplib::DataSink& sink) {
          const std::string event = view.next_event(progress->last, progress->metadata_sent, progress->ended);
          if (!sink.write(event.data(), event.size())) return false;
          if (progress->ended) sink.done();
          return true;
        },
        [&view](bool) {
          std::lock_guard<std::mutex> lock(view.mutex);
          --view.following;
        });
  });
  // A browser that takes nothing for 2 s is let go (it reconnects by itself), so that the end of
  // a run never waits long for one.
  view.server.set_write_timeout(2, 0);
  const std::string where = address + ":" + std::to_string(port);
  view.port = port == 0 ? view.server.bind_to_any_port(address)
                        : (view.server.bind_to_port(address, port) ? port : -1);
  if (view.port <= 0)
    throw app::UserError("--view: cannot serve on " + where +
                         " (the port is taken, or the address is not one of this machine's)");
  view.thread = std::thread([&view] { view.server.listen_after_bind(); });
}

LiveView::~LiveView() {
  finish("s2kf live ended");
  // Lets each browser's stream send its end event before the server closes the connections.
  for (int wait = 0; wait < 100; ++wait) {
    {
      std::lock_guard<std::mutex> lock(impl_->mutex);
      if (impl_->following == 0) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

std::string LiveView::url() const {
  const std::string& host = impl_->address;
  return "http://" + (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" +
         std::to_string(impl_->port) + "/";
}

void LiveView::set_metadata(std::string json) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->metadata = std::move(json);
  impl_->changed.notify_all();
}

bool LiveView::watched() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->following > 0;
}

void LiveView::publish(std::string record) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->record = std::move(record);
  ++impl_->sequence;
  impl_->changed.notify_all();
}

void LiveView::finish(const std::string& why) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (impl_->ended) return;
  impl_->ended = true;
  impl_->end_reason = why;
  for (char& c : impl_->end_reason)
    if (c == '\n' || c == '\r') c = ' ';  // one line of event data
  impl_->changed.notify_all();
}

LiveView::Counts LiveView::counts() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->counts;
}

}  // namespace s2kf::cli
