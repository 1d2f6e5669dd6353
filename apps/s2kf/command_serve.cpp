// `s2kf serve`: stream a C3D recording over the QTM real-time protocol at its rate, as a motion
// capture system would, so that `s2kf live` (and other QTM clients) can be tried without cameras.
#include "command.hpp"
#include "interruption.hpp"

#include <s2kf/io/c3d_error.hpp>
#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/live/qtm_server.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

namespace s2kf::cli {
namespace {

struct ServeSettings {
  std::string input;
  std::string address = "127.0.0.1";
  int port = live::kDefaultPort;
  double rate_hz = 0;
  bool loop = false;
  std::string port_file;  // where the port goes once listening (with --port 0)
  bool quiet = false;
  live::ServeFaults faults;
};

std::atomic<bool> stop_serving{false};

void run_serve(const ServeSettings& settings) {
  std::unique_ptr<c3d::C3dFrameSource> source;
  try {
    source = std::make_unique<c3d::C3dFrameSource>(settings.input);
  } catch (const c3d::C3dError& e) {
    throw UserError(settings.input + ": " + e.sentence());
  } catch (const std::exception& e) {
    throw UserError(e.what());
  }
  if (source->frame_count() == 0) throw UserError(settings.input + ": the recording holds no frame to serve");
  if (settings.rate_hz <= 0 && !c3d::plausible_frame_rate(source->rate_hz()))
    throw UserError(settings.input + ": no plausible frame rate in its header; give --rate");
  live::ServeOptions options;
  options.address = settings.address;
  options.port = static_cast<std::uint16_t>(settings.port);
  options.rate_hz = settings.rate_hz;
  options.loop = settings.loop;
  options.faults = settings.faults;
  std::unique_ptr<live::QtmServer> server;
  try {
    server = std::make_unique<live::QtmServer>(*source, options);
  } catch (const live::ConnectionError& e) {
    throw UserError(e.what());
  }
  if (!settings.port_file.empty()) {
    std::ofstream(settings.port_file + ".tmp") << server->port() << "\n";
    std::rename((settings.port_file + ".tmp").c_str(), settings.port_file.c_str());
  }
  if (!settings.quiet)
    std::cout << "serving " << settings.input << " (" << source->labels().size() << " markers, "
              << source->frame_count() << " frames at " << server->rate_hz() << " Hz"
              << (settings.loop ? ", looped" : "") << ") on " << settings.address << ":" << server->port()
              << " (QTM real-time protocol " << live::kProtocolMajor << "." << live::kProtocolMinor << ")"
              << std::endl;
  // Ctrl-C ends the server at once: it writes no file.
  std::signal(SIGINT, [](int) { stop_serving.store(true); });
  std::signal(SIGTERM, [](int) { stop_serving.store(true); });
  server->run(stop_serving, [&](const std::string& line) {
    if (!settings.quiet) std::cout << line << std::endl;
  });
  if (!settings.quiet) std::cout << "sent " << server->frames_sent() << " frames" << std::endl;
}

const RegisterCommand serve_registration{
    "serve", "Stream a C3D recording over the QTM real-time protocol (for s2kf live and other clients)",
    [](CLI::App& app) {
      auto settings = std::make_shared<ServeSettings>();
      app.add_option("recording", settings->input, "the C3D file to stream")->required();
      app.add_option("--port", settings->port, "TCP port (default 22223, QTM's; 0: one the system chooses)")
          ->check(CLI::Range(0, 65535));
      app.add_option("--address", settings->address,
                     "address to listen on (default 127.0.0.1, this machine only)");
      app.add_option("--rate", settings->rate_hz, "frames per second (default: the recording's)")
          ->check(CLI::Range(1.0, 100000.0));
      app.add_flag("--loop", settings->loop, "start again at the end instead of ending the data");
      app.add_option("--port-file", settings->port_file, "write the port to this file once listening");
      app.add_flag("--quiet", settings->quiet, "print nothing but errors");
      auto* faults = app.add_option_group("Faults", "misbehave on purpose, to test clients");
      faults->add_option("--fault-disconnect-after", settings->faults.disconnect_after,
                         "close the connection once after N frames");
      faults->add_option("--fault-relabel-after", settings->faults.relabel_after,
                         "swap the first two labels (and their markers) after N frames");
      faults->add_option("--fault-unlabel-after", settings->faults.unlabel_after,
                         "stop sending the last label and its marker after N frames, unannounced");
      faults->add_option("--fault-skip-every", settings->faults.skip_every,
                         "leave out every N-th frame number");
      faults->add_option("--fault-malformed-after", settings->faults.malformed_after,
                         "send a packet whose size lies after N frames");
      app.callback([settings] { run_serve(*settings); });
    }};

}  // namespace
}  // namespace s2kf::cli
