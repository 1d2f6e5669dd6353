/// @file
/// Estimating the subject's body height from a recording: distances between markers on the same
/// rigid segment do not change with the pose, so their ratio to the model's gives the scale.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/frame_source.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::calibration {

/// Collects, frame by frame, the distance ratios of every visible pair of mapped markers that ride
/// on the same frame of the model (at least 50 mm apart in the model, so noise stays small), and
/// returns model height x median ratio. Without any such pair it returns nothing.
class HeightEstimator {
 public:
  HeightEstimator(const body::BodyModel& model, body::MarkerMapping mapping)
      : mapping_(std::move(mapping)), height_(model.height_mm) {
    const Eigen::Matrix3Xd zero = body::marker_positions(model, body::zero_pose(model));
    for (int a = 0; a < model.marker_count(); ++a)
      for (int b = a + 1; b < model.marker_count(); ++b) {
        if (model.markers[a].frame != model.markers[b].frame) continue;
        if (mapping_.point_of_marker[a] < 0 || mapping_.point_of_marker[b] < 0) continue;
        const double d = (zero.col(a) - zero.col(b)).norm();
        if (d >= 50.0 * model.height_mm / 1000.0) pairs_.push_back({a, b, d});
      }
  }

  /// Number of rigid marker pairs the recording offers.
  std::size_t pair_count() const { return pairs_.size(); }

  void add_frame(const Eigen::Matrix3Xd& points, const Eigen::Array<bool, Eigen::Dynamic, 1>& visible);

  std::optional<double> height_mm() const;

 private:
  struct Pair {
    int a, b;
    double model_distance;
  };
  body::MarkerMapping mapping_;
  double height_;
  std::vector<Pair> pairs_;
  std::vector<double> ratios_;
};

/// A height and how many rigid pairs it came from.
struct HeightEstimate {
  double mm = 0;
  std::size_t pairs = 0;
};

/// The body height from up to `max_frames` frames spread evenly through the source; nothing when
/// the mapped markers form no rigid pair.
std::optional<HeightEstimate> estimate_height(FrameSource& source, const body::BodyModel& model,
                                              const body::MarkerMapping& mapping,
                                              std::int64_t max_frames = 200);

/// Why the recording's coordinates cannot be a person's in millimetres, or "" when they can. The
/// rigid marker pairs measure the body whatever the file's POINT:UNITS say: `geometric_mm` is the
/// height they give (estimate_height), `height_mm` the height the run would use and `source` where
/// that came from ("given", ...). A metres recording labelled mm gives a geometric height of a
/// few mm, and a given --height cannot hide it: the two then differ a thousandfold.
inline std::string units_problem(double geometric_mm, double height_mm, const std::string& source) {
  const bool estimated = source.rfind("estimated", 0) == 0;
  const double factor = (estimated ? 1750.0 : height_mm) / geometric_mm;  // what the coordinates lack
  if (estimated ? (geometric_mm > 300 && geometric_mm < 3000) : (factor > 0.5 && factor < 2.0)) return "";
  std::string unit;  // the unit the coordinates look like, when one fits within a factor of 1.5
  for (const auto& [name, mm] : {std::pair<const char*, double>{"metres", 1000.0},
                                 {"decimetres", 100.0},
                                 {"inches", 25.4},
                                 {"centimetres", 10.0},
                                 {"micrometres", 1e-3}})
    if (factor > mm / 1.5 && factor < mm * 1.5) unit = name;
  std::ostringstream s;
  s << "the distances between markers on the same segment give a body height of " << std::setprecision(3)
    << geometric_mm << " mm";
  if (!estimated) s << ", but the height " << source << " is " << std::lround(height_mm) << " mm";
  s << ": the coordinates are " << (unit.empty() ? "not in millimetres" : "in " + unit + ", not millimetres")
    << "; correct POINT:UNITS in the file";
  return s.str();
}

}  // namespace s2kf::calibration

#if !defined(S2KF_COMPILED)
#include <s2kf/calibration/height_estimate.hxx>
#endif
