/// @file
/// Marker-set files (data/markersets/<name>.json, schema in docs/real-data.md) to and from
/// s2kf::body::MarkerSet, and the choice of the set for a recording (`--markerset`, `--subject`,
/// automatic). JSON stays out of the tracking library, so this lives in the application layer.
#pragma once

#include <s2kf/app/user_error.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/marker_set_mapping.hpp>
#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/markerset/marker_set_completion.hpp>

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::app {

/// Parses a marker-set document; throws std::invalid_argument with a sentence naming `source` and
/// the entry. Only the form is checked here; validate_marker_set checks it against the model.
body::MarkerSet marker_set_from_json(const nlohmann::json& document, const std::string& source);

/// The document marker_set_from_json reads back to the same set.
nlohmann::json marker_set_to_json(const body::MarkerSet& set);

body::MarkerSet load_marker_set(const std::filesystem::path& path);

/// data/markersets, or $S2KF_DATA_DIR/markersets.
std::filesystem::path marker_set_directory();

std::vector<std::string> bundled_marker_set_names();

/// A bundled set's name ("cmu") or the path of a marker-set / subject file.
body::MarkerSet resolve_marker_set(const std::string& name_or_file);

/// Which marker set a recording is tracked with, and why.
struct MarkerSetChoice {
  body::MarkerSet set;
  std::string source;  ///< "given", "subject file F" or "chosen automatically: ..."
  /// Markers the set does not name, placed by their motion (the set above holds them), and the
  /// labels left out with the reason.
  std::vector<markerset::CompletedMarker> inferred;
  std::vector<markerset::LeftOutPoint> left_out;
};

std::string format_fraction(double value);

/// The hook for `--markerset NAME|FILE` and `--subject FILE` (at most one non-empty; both empty:
/// the bundled set that matches the most labels). `labels` are the recording's point labels
/// (model outputs as empty strings).
MarkerSetChoice choose_marker_set_for(const std::vector<std::string>& labels, const std::string& markerset,
                                      const std::string& subject);

/// What to tell the user about the choice once the session mapped the labels: which set, why, how
/// many of its markers the recording has, which labels were ignored.
std::vector<std::string> marker_set_messages(const MarkerSetChoice& choice,
                                             const body::MarkerMapping& mapping);

/// A calibrated subject as a marker set: explicit frames and offsets at the reference height
/// (1000 mm), the subject's height and the bone-length factors relative to the scaled model, and
/// each marker's noise_mm where `marker_noise_mm` (per model marker, may be empty) has a finite one.
body::MarkerSet subject_marker_set(const body::MarkerSet& original, const body::BodyModel& calibrated,
                                   const std::map<std::string, double>& segment_scale,
                                   const std::vector<double>& marker_noise_mm, const std::string& name);

}  // namespace s2kf::app
