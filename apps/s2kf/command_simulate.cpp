// `s2kf simulate`: a synthetic recording with ground truth (C3D + _truth.csv + _clean.csv).
#include <s2kf/app/bundled_motions.hpp>
#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/app/motion_json.hpp>
#include "command.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/c3d_writer.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using s2kf::cli::motion_names;
using s2kf::cli::number_pair;
using s2kf::cli::resolve_motion;
using s2kf::cli::UserError;

std::string with_suffix(const fs::path& c3d, const std::string& suffix) {
  fs::path stem = c3d;
  stem.replace_extension();
  return stem.string() + suffix;
}

void write_c3d_recording(const fs::path& path, const s2kf::sim::Recording& recording) {
  s2kf::c3d::write_c3d(path.string(), recording.labels, recording.rate_hz, recording.positions,
                       recording.visible);
}

void write_clean_csv(const std::string& path, const s2kf::sim::Recording& recording) {
  s2kf::io::write_file_atomically(path, [&](std::ostream& out) {
    out << "frame,time";
    for (const auto& name : recording.labels) out << "," << name << "_x," << name << "_y," << name << "_z";
    out << "\n";
    char buffer[64];
    for (Eigen::Index k = 0; k < recording.frames(); ++k) {
      std::snprintf(buffer, sizeof buffer, "%ld,%.9g", static_cast<long>(k), recording.time_s(k));
      out << buffer;
      const auto& clean = recording.clean[static_cast<std::size_t>(k)];
      for (Eigen::Index m = 0; m < clean.cols(); ++m)
        for (int c = 0; c < 3; ++c) {
          std::snprintf(buffer, sizeof buffer, ",%.9g", clean(c, m));
          out << buffer;
        }
      out << "\n";
    }
  });
}

struct Settings {
  std::string motion;
  std::uint64_t seed = 1;
  double height_mm = s2kf::sim::SubjectOptions{}.height_mm;
  long frames = 0;
  double rate = 100.0;
  std::string occlusion;
  double noise_mm = s2kf::sim::SubjectOptions{}.noise_sd_mm;
  double placement_mm = s2kf::sim::SubjectOptions{}.placement_sd_mm;
  double soft_tissue_mm = s2kf::sim::SubjectOptions{}.soft_tissue_mm;
  double segment_scale_sd = s2kf::sim::SubjectOptions{}.segment_scale_sd;
  std::vector<std::string> blackouts;
  std::vector<std::string> dropouts;
  std::string out;
  std::string markerset;  // empty: the model's own 50 markers
  bool list = false;
};

void run(const Settings& settings) {
  if (settings.list) {
    for (const auto& name : motion_names()) std::cout << name << "\n";
    return;
  }
  if (settings.motion.empty())
    throw UserError("simulate needs --motion NAME (see --list) or --motion FILE.json");
  if (settings.out.empty())
    throw UserError("simulate needs --out FILE.c3d to know where to write the recording");
  if (!(settings.height_mm >= 500.0 && settings.height_mm <= 2500.0))
    throw UserError("--height must lie between 500 and 2500 mm");
  if (!(settings.rate > 0.0 && settings.rate <= 10000.0)) throw UserError("--rate must lie in (0, 10000] Hz");
  if (settings.frames < 0) throw UserError("--frames must not be negative");
  if (!(settings.noise_mm >= 0.0 && settings.noise_mm <= 1000.0))
    throw UserError("--noise must lie in [0, 1000] mm");
  if (!(settings.placement_mm >= 0.0 && settings.placement_mm <= 1000.0))
    throw UserError("--placement must lie in [0, 1000] mm");
  if (!(settings.soft_tissue_mm >= 0.0 && settings.soft_tissue_mm <= 1000.0))
    throw UserError("--soft-tissue must lie in [0, 1000] mm");
  if (!(settings.segment_scale_sd >= 0.0 && settings.segment_scale_sd <= 0.2))
    throw UserError("--segment-scale must lie in [0, 0.2] (a relative standard deviation)");

  s2kf::sim::RecordingOptions options;
  options.frame_rate = settings.rate;
  options.frames = settings.frames;
  if (!settings.occlusion.empty()) options.occlusion = s2kf::cli::occlusion_option(settings.occlusion);
  for (const auto& text : settings.blackouts) {
    const auto [start, duration] = number_pair(text, "--blackout", "START_S,DURATION_S (e.g. 2,1)");
    if (!(start >= 0.0 && duration >= 0.0))
      throw UserError("--blackout: start and duration must not be negative");
    options.blackouts.push_back({start, duration});
  }
  for (const auto& text : settings.dropouts) {
    const auto comma = text.find(',');
    if (comma == std::string::npos)
      throw UserError("--dropout expects SEGMENT,START_S,DURATION_S, not '" + text + "'");
    const auto [start, duration] =
        number_pair(text.substr(comma + 1), "--dropout", "SEGMENT,START_S,DURATION_S (e.g. LE,2,0.5)");
    if (!(start >= 0.0 && duration >= 0.0))
      throw UserError("--dropout: start and duration must not be negative");
    options.segment_dropouts.push_back({text.substr(0, comma), start, duration});
  }

  s2kf::sim::SubjectOptions subject_options;
  subject_options.height_mm = settings.height_mm;
  subject_options.noise_sd_mm = settings.noise_mm;
  subject_options.placement_sd_mm = settings.placement_mm;
  subject_options.soft_tissue_mm = settings.soft_tissue_mm;
  subject_options.segment_scale_sd = settings.segment_scale_sd;
  auto base = s2kf::body::mmm_body_model(settings.height_mm);
  // The subject wears another set (Plug-in Gait, CMU): its labels and places.
  if (!settings.markerset.empty())
    base = s2kf::body::apply_marker_set(s2kf::body::mmm_body_model(1000),
                                        s2kf::app::resolve_marker_set(settings.markerset))
               .scaled(settings.height_mm);
  const s2kf::sim::Subject subject = s2kf::sim::make_subject(base, subject_options, settings.seed);

  const fs::path motion_file = resolve_motion(settings.motion);
  s2kf::cli::JointTable joints{subject.joint_names, subject.lower, subject.upper};
  s2kf::sim::KeyframeMotion motion;
  s2kf::sim::Recording recording;
  try {
    motion = s2kf::cli::load_motion_file(motion_file, joints, settings.seed);
    for (const auto& dropout : options.segment_dropouts)
      s2kf::sim::markers_of_segment(subject, dropout.segment);
    recording = s2kf::sim::simulate_recording(motion, subject, options, settings.seed);
  } catch (const std::invalid_argument& e) {
    throw UserError(e.what());
  } catch (const std::out_of_range& e) {
    throw UserError(e.what());
  }

  const fs::path out(settings.out);
  const std::string truth_path = with_suffix(out, "_truth.csv");
  const std::string clean_path = with_suffix(out, "_clean.csv");
  try {
    write_c3d_recording(out, recording);
    s2kf::io::save_motion_csv(truth_path, s2kf::sim::truth_motion(recording, subject.joint_names));
    write_clean_csv(clean_path, recording);
  } catch (const std::runtime_error& e) {
    throw UserError(e.what());
  }

  const double hidden = recording.hidden_fraction();
  std::printf("simulated '%s' (%s): %ld frames at %g Hz, %ld markers, subject %.0f mm, seed %llu\n",
              motion.name.c_str(), motion_file.string().c_str(), static_cast<long>(recording.frames()),
              recording.rate_hz, static_cast<long>(recording.markers()), settings.height_mm,
              static_cast<unsigned long long>(settings.seed));
  std::printf("hidden: %.1f %% of marker-frames (%.1f of %ld markers per frame on average)\n", 100.0 * hidden,
              hidden * static_cast<double>(recording.markers()), static_cast<long>(recording.markers()));
  std::printf("wrote %s\nwrote %s\nwrote %s\n", out.string().c_str(), truth_path.c_str(), clean_path.c_str());
}

const s2kf::cli::RegisterCommand simulate_registration{
    "simulate", "Make a synthetic recording with ground truth (C3D, _truth.csv, _clean.csv)",
    [](CLI::App& app) {
      auto settings = std::make_shared<Settings>();
      app.add_option("--motion", settings->motion, "Bundled motion name (see --list) or a motion .json file");
      app.add_option("--seed", settings->seed,
                     "Seed of every random draw (subject, noise, occlusion, sweep)");
      app.add_option("--height", settings->height_mm, "Subject height in mm")->capture_default_str();
      app.add_option("--frames", settings->frames, "Number of frames (default: the motion's length)");
      app.add_option("--rate", settings->rate, "Frame rate in Hz")->capture_default_str();
      app.add_option("--occlusion", settings->occlusion,
                     "Random occlusion p,lambda: per frame each visible marker vanishes with probability p "
                     "for Poisson(lambda) frames (the paper: 0.005,100)");
      app.add_option("--noise", settings->noise_mm, "Sensor noise SD per coordinate, mm")
          ->capture_default_str();
      app.add_option("--placement", settings->placement_mm, "Marker placement offset SD per coordinate, mm")
          ->capture_default_str();
      app.add_option("--soft-tissue", settings->soft_tissue_mm, "Soft-tissue artefact scale, mm")
          ->capture_default_str();
      app.add_option("--segment-scale", settings->segment_scale_sd,
                     "Relative SD of the segment length factors")
          ->capture_default_str();
      app.add_option("--blackout", settings->blackouts, "Hide every marker: START_S,DURATION_S (repeatable)");
      app.add_option("--dropout", settings->dropouts,
                     "Hide the markers of one segment: SEGMENT,START_S,DURATION_S (repeatable)");
      app.add_option("--out", settings->out,
                     "Output C3D file; FILE_truth.csv and FILE_clean.csv go beside it");
      app.add_option("--markerset", settings->markerset,
                     "the markers the subject wears: a bundled marker set (kit, cmu, plugin_gait) or a "
                     ".json file (default: the model's own 50)");
      app.add_flag("--list", settings->list, "List the bundled motions");
      app.callback([settings] { run(*settings); });
    }};

}  // namespace
