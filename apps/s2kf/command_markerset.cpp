// `s2kf markerset infer REC.c3d --out SET.json`: a marker set inferred from a recording whose labels
// no bundled set names (track/marker_set_inference.hpp), written for a person to read and correct.
#include <s2kf/app/inferred_marker_set.hpp>
#include "command.hpp"

#include <iomanip>
#include <iostream>
#include <memory>
#include <string>

namespace s2kf::cli {
namespace {

struct InferSettings {
  std::string input;
  std::string out;
  std::string up = "auto";
  bool quiet = false;
};

void run_infer(const InferSettings& settings) {
  const int up = settings.up == "auto" ? -1 : settings.up == "x" ? 0 : settings.up == "y" ? 1 : 2;
  const markerset::InferredMarkerSet inferred = infer_marker_set_file(settings.input, settings.out, up);
  if (settings.quiet) return;
  for (const std::string& note : inferred.notes) std::cout << note << "\n";
  std::cout << inferred.clusters.clusters.size() << " rigid clusters; " << inferred.rounds
            << " round(s) of tracking and reassignment; body height " << std::lround(inferred.height_mm)
            << " mm; RMS spread of the markers on their segments " << std::fixed << std::setprecision(1)
            << inferred.spread_mm << " mm\n";
  std::cout << "segment  markers  spread (mm)  confidence\n";
  for (const markerset::InferredSegment& s : inferred.segments)
    std::cout << std::left << std::setw(9) << s.segment << std::right << std::setw(7) << s.markers
              << std::setw(13) << s.spread_mm << std::setw(11) << std::lround(100 * s.confidence) << " %\n";
  std::cout << "Wrote " << settings.out << " (" << inferred.set.entries.size()
            << " markers); track with --markerset " << settings.out << ".\n";
}

const RegisterCommand markerset_registration{
    "markerset", "Marker sets: infer one from a recording whose labels no bundled set names",
    [](CLI::App& app) {
      app.require_subcommand(1);
      CLI::App* infer = app.add_subcommand(
          "infer", "Infer which segment each marker rides on, and where, from the recording's motion");
      auto settings = std::make_shared<InferSettings>();
      infer
          ->add_option("recording", settings->input,
                       "C3D recording (any motion; the subject need not stand at the start)")
          ->required();
      infer->add_option("--out", settings->out, "marker-set file to write (JSON)")->required();
      infer->add_option("--up", settings->up, "the recording's vertical axis: x, y, z or auto (default)")
          ->check(CLI::IsMember({"auto", "x", "y", "z"}));
      infer->add_flag("--quiet", settings->quiet, "print nothing but errors");
      infer->callback([settings] { run_infer(*settings); });
    }};

}  // namespace
}  // namespace s2kf::cli
