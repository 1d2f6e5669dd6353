// `s2kf simulate`: a synthetic recording with ground truth (C3D + _truth.csv + _clean.csv).
#include "command.hpp"
#include "motion_json.hpp"

#include <s2kf/body/body_model.hpp>
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
using s2kf::cli::UserError;

fs::path data_directory() {
  if (const char* from_environment = std::getenv("S2KF_DATA_DIR"); from_environment && *from_environment)
    return from_environment;
#ifdef S2KF_DATA_DIR
  return S2KF_DATA_DIR;
#else
  return fs::path(__FILE__).parent_path().parent_path().parent_path() / "data";
#endif
}

fs::path motions_directory() { return data_directory() / "motions"; }

std::vector<std::string> motion_names() {
  std::vector<std::string> names;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(motions_directory(), error))
    if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

// A name of a bundled motion or the path of a motion file.
fs::path resolve_motion(const std::string& motion) {
  const fs::path as_path(motion);
  if (as_path.extension() == ".json") {
    if (!fs::exists(as_path)) throw UserError("the motion file " + motion + " does not exist");
    return as_path;
  }
  const fs::path bundled = motions_directory() / (motion + ".json");
  if (fs::exists(bundled)) return bundled;
  std::string known;
  for (const auto& name : motion_names()) known += (known.empty() ? "" : ", ") + name;
  throw UserError("unknown motion '" + motion +
                  "' (known: " + (known.empty() ? "none found in " + motions_directory().string() : known) +
                  "; or give a .json file)");
}

// "a,b" -> two numbers, or a UserError naming the option.
std::pair<double, double> number_pair(const std::string& text, const std::string& option,
                                      const std::string& form) {
  std::istringstream in(text);
  double a = 0, b = 0;
  char comma = 0;
  if (!(in >> a >> comma >> b) || comma != ',' || !(in >> std::ws).eof() || !std::isfinite(a) ||
      !std::isfinite(b))
    throw UserError(option + " expects " + form + ", not '" + text + "'");
  return {a, b};
}

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

void write_truth_csv(const std::string& path, const s2kf::sim::Recording& recording,
                     const std::vector<std::string>& joint_names) {
  s2kf::io::MotionTable table;
  table.joint_names = joint_names;
  table.values.resize(recording.frames(), static_cast<Eigen::Index>(6 + joint_names.size()));
  for (Eigen::Index k = 0; k < recording.frames(); ++k) {
    const auto& pose = recording.truth[static_cast<std::size_t>(k)];
    table.frame.push_back(static_cast<long>(k));
    table.time.push_back(recording.time_s(k));
    table.values.row(k).head<3>() = pose.root_position.transpose();
    table.values.row(k).segment<3>(3) = pose.root_rpy.transpose();
    table.values.row(k).tail(static_cast<Eigen::Index>(joint_names.size())) = pose.joints.transpose();
  }
  s2kf::io::save_motion_csv(path, table);
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
  if (!settings.occlusion.empty()) {
    const auto [p, lambda] = number_pair(settings.occlusion, "--occlusion", "p,lambda (e.g. 0.005,100)");
    if (!(p >= 0.0 && p <= 1.0)) throw UserError("--occlusion: the probability p must lie in [0, 1]");
    if (!(lambda >= 0.0 && lambda <= s2kf::sim::kMaxPoissonMean))
      throw UserError("--occlusion: the mean length lambda must lie in [0, 100000] frames");
    options.occlusion = {p, lambda};
  }
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
  const auto base = s2kf::body::mmm_body_model(settings.height_mm);
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
    write_truth_csv(truth_path, recording, subject.joint_names);
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
      app.add_flag("--list", settings->list, "List the bundled motions");
      app.callback([settings] { run(*settings); });
    }};

}  // namespace
