// `s2kf live HOST[:PORT]`: track a motion capture system's stream (the QTM real-time protocol) as
// it arrives, with the tracker `s2kf track` uses, sending every pose out as it is made (JSON lines
// or OSC over UDP, the live view in a browser), and write the same files as `s2kf track` when the
// stream ends.
#include <s2kf/app/calibrated_subject.hpp>
#include <s2kf/app/track_summary.hpp>
#include "command.hpp"
#include "interruption.hpp"
#include "live_view.hpp"
#include "osc_message.hpp"
#include "output_options.hpp"
#include "track_file.hpp"
#include "viewer/page_writer.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/live/live_feed.hpp>
#include <s2kf/live/live_frame_source.hpp>
#include <s2kf/live/udp_sender.hpp>
#include <s2kf/track/quantile_histogram.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace s2kf::cli {
namespace {

namespace fs = std::filesystem;

struct LiveSettings {
  std::string address;  // HOST[:PORT]
  TrackSettings track;
  double calibration_seconds = 10;
  long frames = -1;
  double seconds = -1;
  int backlog = 16;  // 53 ms at 300 Hz: rides out the pauses of a busy machine (docs/live.md)
  double reconnect_seconds = 10;
  double max_gap_seconds = 1;
  std::string udp_json;  // HOST:PORT
  std::string osc;       // HOST:PORT
  bool view = false;     // --view given
  int view_port = 0;     // 0: the system chooses
  std::string view_address = "127.0.0.1";
};

/// HOST, HOST:PORT, [IPv6]:PORT.
std::pair<std::string, std::uint16_t> split_address(const std::string& text, std::uint16_t default_port) {
  std::string host = text;
  std::string port;
  if (!text.empty() && text.front() == '[') {
    const std::size_t close = text.find(']');
    if (close == std::string::npos) throw UserError("the address " + text + " opens [ but does not close it");
    host = text.substr(1, close - 1);
    if (close + 1 < text.size()) {
      if (text[close + 1] != ':')
        throw UserError("the address " + text + " has something after ] that is not :PORT");
      port = text.substr(close + 2);
    }
  } else if (std::count(text.begin(), text.end(), ':') == 1) {
    host = text.substr(0, text.find(':'));
    port = text.substr(text.find(':') + 1);
  }
  if (host.empty()) throw UserError("the address " + text + " names no host");
  if (port.empty()) return {host, default_port};
  char* end = nullptr;
  const long value = std::strtol(port.c_str(), &end, 10);
  if (*end != '\0' || value < 1 || value > 65535)
    throw UserError("the port in " + text + " is not 1 to 65535");
  return {host, static_cast<std::uint16_t>(value)};
}

/// One UDP datagram per tracked frame: {"frame":F,"time":T,"tracked":true,"pose":{"root_x":...}}.
std::string pose_message(const track::TrackedFrame& row, const std::vector<std::string>& columns) {
  std::ostringstream out;
  out.precision(9);
  out << "{\"frame\":" << row.frame << ",\"time\":" << row.time
      << ",\"visible_markers\":" << row.visible_markers << ",\"pose\":{";
  for (Eigen::Index c = 0; c < row.values.size(); ++c) {
    out << (c ? "," : "") << '"' << columns[static_cast<std::size_t>(c)] << "\":";
    if (std::isfinite(row.values(c)))
      out << row.values(c);
    else
      out << "null";
  }
  out << "}}\n";
  return out.str();
}

/// The UDP output of `option` (HOST:PORT), none when not given.
std::optional<live::UdpSender> udp_output(const std::string& option, const std::string& address) {
  std::optional<live::UdpSender> sender;
  if (address.empty()) return sender;
  const auto [host, port] = split_address(address, 0);
  if (port == 0) throw UserError(option + " needs HOST:PORT");
  try {
    sender.emplace(host, port);
  } catch (const live::ConnectionError& e) {
    throw UserError(option + ": " + e.what());
  }
  return sender;
}

/// The live view's metadata: the page's (docs/viewer.md) for the session's model, marked live,
/// with the frames its plots keep (10 s).
std::string live_view_metadata(const viewer::PageData& layout, const body::BodyModel& model,
                               const std::string& name, double rate) {
  nlohmann::json meta = viewer::page_metadata(layout, model, name, rate, nlohmann::json::object());
  meta["live"] = true;
  meta["live_window_frames"] = std::max<long>(1, std::lround(10 * rate));
  return meta.dump();
}

void run_live(LiveSettings settings) {
  TrackSettings& track = settings.track;
  if (!track.request.markerset.empty() && !track.request.subject.empty())
    throw UserError("give --markerset or --subject, not both (a subject file is a calibrated marker set)");
  const auto [host, port] = split_address(settings.address, live::kDefaultPort);
  const std::string name = host + ":" + std::to_string(port);
  const std::string prefix = track.out.empty() ? "live" : track.out;
  check_outputs(track.outputs, {prefix}, false);
  std::optional<live::UdpSender> udp = udp_output("--udp-json", settings.udp_json);
  std::optional<live::UdpSender> osc = udp_output("--osc", settings.osc);
  std::unique_ptr<LiveView> view;
  if (settings.view) {
    view =
        std::make_unique<LiveView>(settings.view_address, settings.view_port, viewer::live_viewer_page(name));
    std::cout << "s2kf live: the live view is at " << view->url() << std::endl;
  }

  let_first_signal_end_stream();
  live::FeedOptions feed_options;
  feed_options.backlog = static_cast<std::size_t>(settings.backlog);
  feed_options.reconnect_seconds = settings.reconnect_seconds;
  feed_options.log = [quiet = track.quiet](const std::string& line) {
    if (!quiet) std::cerr << "s2kf live: " << line << std::endl;
  };
  std::unique_ptr<live::LiveFeed> feed;
  try {
    feed = std::make_unique<live::LiveFeed>(host, port, feed_options);
  } catch (const live::ConnectionError& e) {
    throw UserError(e.what());
  } catch (const live::ProtocolError& e) {
    throw UserError(name + ": " + e.what());
  }
  const double rate = feed->parameters().rate_hz;
  if (!track.quiet)
    std::cerr << "s2kf live: connected to " << name << ": " << feed->parameters().labels.size()
              << " labels at " << rate << " Hz" << std::endl;

  live::LiveSourceOptions source_options;
  source_options.max_frames = settings.frames;
  source_options.max_seconds = settings.seconds;
  source_options.max_gap_seconds = settings.max_gap_seconds;
  source_options.stop_requested = [] { return stream_end_requested(); };
  live::LiveFrameSource source(*feed, source_options);
  // The session is prepared on a first stretch: a calibrated subject needs one second (the height
  // check), a calibration --calibration-seconds.
  const bool calibrating = track.request.subject.empty() && track.request.calibrate;
  const double first_seconds = calibrating ? settings.calibration_seconds : 1.0;
  const auto first_frames = std::max<std::int64_t>(1, std::llround(first_seconds * rate));
  if (!track.quiet && calibrating)
    std::cerr << "s2kf live: calibrating the subject on the first " << first_frames << " frames" << std::endl;
  const MarkerSequence& first = source.hold_first(first_frames);
  if (first.frame_count() == 0)
    throw UserError(name + ": the stream ended before its first frame (" + feed->ended_reason() + ")");
  SequenceFrameSource prepare(first);

  TrackInput input;
  input.name = name;
  input.stem = "live";
  input.prepare = &prepare;
  input.frames = &source;
  input.rate_hz = rate;
  input.frame_count = -1;
  if (calibrating) {  // else the first stretch may be shorter than a calibration needs (--frames 5)
    if (first.frame_count() < 10)
      throw UserError(name + ": the calibration needs at least 10 frames, the stream gave " +
                      std::to_string(first.frame_count()) + " (give --subject or --no-calibrate)");
    track.request.calibration_frames = static_cast<long>(first.frame_count());
  }
  track.request.calibration_threads = every_core();  // one stream: its calibration may take every core
  // The first seconds are calibrated as they are: tracking does not wait for a still stretch.
  track.request.static_stretch = false;

  // The row's values are the pose columns after frame and time.
  std::vector<std::string> columns = body::pose_column_names(body::mmm_body_model(1000).joint_names());
  columns.erase(columns.begin(), columns.begin() + 2);
  track::QuantileHistogram latency_ms;  // once caught up with the held first stretch; fixed memory
  long deadline_misses = 0;
  long catch_up_frames = 0;  // tracked while catching up: late by design, kept apart
  double catch_up_max_ms = 0;
  const double period_ms = 1000.0 / rate;
  TrackHooks hooks;
  long dropped_preparing = -1;  // frames dropped before the first row: while the session was prepared
  // The live view draws each row with the session's model and the frame as read.
  const pipeline::Session* session = nullptr;
  viewer::PageData layout;
  MarkerFrame last_read;
  last_read.index = -1;
  hooks.on_prepared = [&](const pipeline::Session& prepared) {
    session = &prepared;
    if (!view) return;
    layout = viewer::page_layout(prepared.model, prepared.mapping, false);
    view->set_metadata(live_view_metadata(layout, prepared.model, name, rate));
  };
  hooks.on_read = [&](const MarkerFrame& frame) {
    if (view && view->watched()) last_read = frame;
  };
  hooks.on_row = [&](const track::TrackedFrame& row) {
    if (dropped_preparing < 0) dropped_preparing = feed->counts().dropped;
    if (udp) udp->send(pose_message(row, columns));
    if (osc) {
      const std::vector<char> message = osc_pose_message(row);
      osc->send(message.data(), message.size());
    }
    if (view && session && last_read.index == row.frame && view->watched()) {
      std::string record;
      viewer::append_record(layout, session->model, session->mapping, static_cast<double>(row.frame),
                            row.time, row.values, last_read, record);
      view->publish(viewer::base64_encode(record));
    }
    if (row.frame == source.last_arrival_index()) {
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - source.last_arrival())
              .count();
      if (feed->catching_up()) {
        ++catch_up_frames;
        catch_up_max_ms = std::max(catch_up_max_ms, ms);
      } else {
        latency_ms.add(ms);
        if (ms > period_ms) ++deadline_misses;
      }
    }
  };
  hooks.on_summary = [&](nlohmann::json& summary) {
    const live::FeedCounts counts = feed->counts();
    nlohmann::json live;
    live["address"] = name;
    live["protocol"] =
        "QTM real-time " + std::to_string(live::kProtocolMajor) + "." + std::to_string(live::kProtocolMinor);
    live["rate_hz"] = rate;
    live["end"] = source.stopped()   ? std::string("stopped by a signal")
                  : source.limited() ? std::string("--frames or --seconds reached")
                                     : feed->ended_reason();
    live["frames_received"] = counts.received;
    live["frames_dropped_busy"] = counts.dropped;
    live["frames_dropped_preparing"] = std::max(0L, dropped_preparing);
    live["frames_missing"] = source.missing_frames();
    live["frames_filled"] = source.filled_frames();
    live["calibration_frames"] = first.frame_count();
    live["reconnects"] = counts.reconnects;
    live["label_changes"] = counts.label_changes;
    nlohmann::json& latency = live["latency_ms"];
    latency["frames"] = latency_ms.count();
    latency["median"] = latency_ms.quantile(0.5);
    latency["p99"] = latency_ms.quantile(0.99);
    latency["max"] = latency_ms.max();
    latency["deadline_ms"] = period_ms;
    latency["deadline_misses"] = deadline_misses;
    live["catch_up"] = {{"frames", catch_up_frames}, {"max_ms", catch_up_max_ms}};
    if (udp)
      live["udp_json"] = {{"address", settings.udp_json}, {"sent", udp->sent()}, {"dropped", udp->dropped()}};
    if (osc) live["osc"] = {{"address", settings.osc}, {"sent", osc->sent()}, {"dropped", osc->dropped()}};
    if (view) {
      const LiveView::Counts counts = view->counts();
      live["view"] = {{"address", view->url()},
                      {"browsers", counts.browsers},
                      {"frames_sent", counts.sent},
                      {"frames_skipped", counts.skipped}};
    }
    summary["live"] = live;
  };
  if (fs::path(prefix).has_parent_path()) fs::create_directories(fs::path(prefix).parent_path());
  TrackOutcome outcome = track_source(input, prefix, track, false, hooks);
  const bool failed = feed->failed();
  const std::string why = feed->ended_reason();
  feed->stop();
  if (view) view->finish(outcome.summary["live"]["end"].get<std::string>());
  if (!track.quiet) {
    std::cout << outcome.paragraph << "\n";
    const nlohmann::json& live = outcome.summary["live"];
    std::cout << "Stream: " << live["frames_received"] << " frames received, " << live["frames_dropped_busy"]
              << " dropped while busy, " << live["frames_missing"] << " missing; latency median "
              << fixed_text(live["latency_ms"]["median"].get<double>(), 3) << " ms, p99 "
              << fixed_text(live["latency_ms"]["p99"].get<double>(), 3)
              << " ms; ended: " << live["end"].get<std::string>() << ".\n";
  }
  if (failed)
    throw UserError(name + ": " + why + "; the " + std::to_string(outcome.summary.value("frames", 0L)) +
                    " frames tracked until then are written");
}

const RegisterCommand live_registration{
    "live", "Track a motion capture system's stream (QTM real-time protocol) as it arrives",
    [](CLI::App& app) {
      auto settings = std::make_shared<LiveSettings>();
      TrackSettings& track = settings->track;
      app.add_option("address", settings->address, "the server, HOST or HOST:PORT (default port 22223)")
          ->required();
      app.add_option("--out", track.out, "prefix of the output files (default: live)");
      app.add_option("--markerset", track.request.markerset,
                     "marker set: a bundled name or a JSON file (default: the best)");
      app.add_option("--subject", track.request.subject, "calibrated subject file written by s2kf calibrate");
      app.add_option("--calibration-seconds", settings->calibration_seconds,
                     "calibrate the subject on this first stretch of the stream (default 10)")
          ->check(CLI::Range(0.1, 3600.0));
      app.add_flag("!--no-calibrate", track.request.calibrate,
                   "track with the marker set's subject as it is");
      app.add_option("--height", track.request.height_mm, "body height in mm (default: estimated)")
          ->check(CLI::Range(300.0, 3000.0));
      app.add_option("--samples", track.request.samples, "S2KF sample count (default 301)")
          ->check(CLI::Range(3, 100001));
      app.add_option("--preset", track.request.preset, "noise preset: default or paper")
          ->check(CLI::IsMember({"default", "paper"}));
      app.add_option("--frames", settings->frames, "end after N frames")->check(CLI::PositiveNumber);
      app.add_option("--seconds", settings->seconds, "end after S seconds of stream")
          ->check(CLI::PositiveNumber);
      app.add_option("--backlog", settings->backlog,
                     "frames kept while the tracker is busy; older ones are dropped and counted (default 16)")
          ->check(CLI::Range(1, 1000000));
      app.add_option("--reconnect-seconds", settings->reconnect_seconds,
                     "after a lost connection, try again for this long (default 10)")
          ->check(CLI::Range(0.0, 86400.0));
      app.add_option("--max-gap", settings->max_gap_seconds,
                     "missing frames up to this many seconds are predicted frame by frame (default 1)")
          ->check(CLI::Range(0.0, 60.0));
      app.add_option("--udp-json", settings->udp_json,
                     "send every pose as one JSON line to HOST:PORT over UDP");
      app.add_option("--osc", settings->osc,
                     "send every pose as one OSC message /s2kf/pose to HOST:PORT over UDP");
      CLI::Option* view =
          app.add_option("--view", settings->view_port,
                         "serve the live view in a browser on this port (default: one the system chooses)")
              ->expected(0, 1)
              ->check(CLI::Range(0, 65535));
      app.add_option("--view-address", settings->view_address,
                     "the address the live view listens on (default 127.0.0.1, this machine only)");
      app.add_flag("--quiet", track.quiet, "print nothing but errors");
      add_output_options(app, track.outputs);
      app.callback([settings, view] {
        settings->view = view->count() > 0;
        run_live(*settings);
      });
    }};

}  // namespace
}  // namespace s2kf::cli
