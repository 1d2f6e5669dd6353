/// @file
/// Inferring a marker set for a recording whose labels no known set names: which segment of the
/// body model each marker rides on, and where. See docs/real-data.md ("Inferring a marker set").
///
/// 1. Rigid clusters (rigid_clusters.hpp): a recording in which nothing moves against anything
///    else cannot be told apart and is refused.
/// 2. A template fit in the first frame that shows the most markers (the subject is expected to
///    stand there, as recordings start): the model at its zero pose, arms down to out sideways,
///    scaled and turned about the recording's vertical, its surface given by the markers of the
///    known sets (the places where labs put markers). Each marker takes the frame of the nearest
///    template marker. The facing direction must win clearly, or the recording is refused.
/// 3. Rounds of tracking and reassignment: the recording is tracked with the current set; each
///    marker then moves to the model frame in which its position stays most constant over the
///    tracked frames, at its mean position there (a fit over many frames). Rounds end when no
///    marker moves.
/// 4. Confidence: a marker's is 1 - (its spread on its segment) / (its spread on the best other
///    segment); a segment's is the mean over its markers. A fit that leaves the markers far from
///    rigid on any segment is refused.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/core/label_text.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/track/rigid_clusters.hpp>
#include <s2kf/track/session.hpp>
#include <s2kf/track/tracker.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::track {

struct MarkerSetInferenceOptions {
  /// The recording's vertical: 0, 1 or 2 for x, y or z up; -1: the axis along which the markers
  /// of the template frame spread furthest (a standing subject is taller than wide).
  int up_axis = -1;
  TrackerOptions tracker;  ///< for the rounds of tracking (fewer samples are enough)
  long frames = 600;       ///< frames tracked per round at most, from the start
  long skip_frames = 20;   ///< tracked frames left out at the start of each round (convergence)
  int max_rounds = 4;
  RigidClusterOptions clusters;
  /// Refusals: the facing direction of the template fit must beat every direction more than 60
  /// degrees away by this factor of cost; the markers' RMS spread on their segments must stay
  /// below max_spread_mm.
  double heading_margin = 1.1;
  double max_spread_mm = 30.0;
  /// A marker moves to another frame only where its spread is below this fraction of its spread
  /// on its current frame: a segment that barely moves against its neighbour in the recording
  /// (the lumbar spine against the pelvis in a walk) leaves its markers where the template put them.
  double move_ratio = 0.6;
  /// A marker whose spread on its frame stays below this rides on it well enough and stays: where a
  /// joint hardly moved in the recording (a wrist held straight), the neighbour fits as well and
  /// only the template can tell them apart. 15 mm: twice the simulated subjects' soft tissue.
  double rigid_spread_mm = 15.0;
  /// Known marker sets whose markers (besides the base model's own) describe the body surface for
  /// the template fit.
  std::vector<body::MarkerSet> known_sets;
};

/// How well one segment's markers were placed.
struct InferredSegment {
  std::string segment;
  int markers = 0;
  double spread_mm = 0;   ///< RMS over its markers of their spread on it over the tracked frames
  double confidence = 0;  ///< mean over its markers of 1 - spread on it / spread on the best other
};

struct InferredMarkerSet {
  body::MarkerSet set;  ///< explicit frames and offsets at 1000 mm, labels as recorded
  double height_mm = 0;
  int up_axis = 2;
  long template_frame = 0;
  int rounds = 0;
  RigidClusters clusters;
  std::vector<InferredSegment> segments;  ///< the segments that carry markers, in model order
  double spread_mm = 0;                   ///< RMS over all markers
  std::vector<std::string> notes;         ///< what was done, one sentence each
};

namespace detail {

/// A place on the body where some lab puts a marker: its frame and where it is at the zero pose of
/// the 1000 mm model.
struct TemplatePoint {
  int frame = 0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< in its frame
};

inline std::vector<TemplatePoint> template_points(const body::BodyModel& base,
                                                  const std::vector<body::MarkerSet>& sets) {
  std::vector<TemplatePoint> points;
  for (const body::Marker& marker : base.markers) points.push_back({marker.frame, marker.offset});
  for (const body::MarkerSet& set : sets)
    for (const body::Marker& marker : body::apply_marker_set(base, set).markers)
      points.push_back({marker.frame, marker.offset});
  return points;
}

/// The zero pose with both arms turned out sideways by `abduction` (rad).
inline Eigen::VectorXd arms_out(const body::BodyModel& base, double abduction) {
  Eigen::VectorXd joints = Eigen::VectorXd::Zero(base.joint_count());
  joints(base.joint_index("LSy")) = abduction;
  joints(base.joint_index("RSy")) = -abduction;
  return joints;
}

/// Lab-from-model rotation for model z along lab axis `up` and the model's x turned by `heading`
/// about it (right-handed: the other two lab axes in cyclic order).
inline Eigen::Matrix3d lab_from_model(int up, double heading) {
  const Eigen::Matrix3d lab = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d a = lab.col((up + 1) % 3), b = lab.col((up + 2) % 3);
  Eigen::Matrix3d r;
  r.col(0) = std::cos(heading) * a + std::sin(heading) * b;
  r.col(1) = -std::sin(heading) * a + std::cos(heading) * b;
  r.col(2) = lab.col(up);
  return r;
}

/// Per point and model frame: the RMS spread (mm) of the point's position in that frame over the
/// tracked frames, and its mean position there.
struct FrameSpread {
  Eigen::MatrixXd spread;                          ///< points x frames; infinity where never seen
  std::vector<std::vector<Eigen::Vector3d>> mean;  ///< [point][frame], mm at the tracked height
};

inline FrameSpread track_and_measure(const MarkerSequence& recording, const std::vector<int>& points,
                                     const body::MarkerSet& set, double height_mm, const SampleSet& samples,
                                     const MarkerSetInferenceOptions& options, double& estimated_height_mm) {
  MarkerSequence head = recording.frames(0, std::min<Eigen::Index>(recording.frame_count(), options.frames));
  SequenceFrameSource source(head);
  SessionOptions session_options;
  session_options.tracker = options.tracker;
  session_options.calibrate = false;
  session_options.height_mm = height_mm;
  const Session session = prepare_session(source, set, session_options, samples);
  estimated_height_mm = session.height_mm;
  const body::BodyModel& model = session.model;
  const int frames = model.frame_count();
  const auto n = static_cast<Eigen::Index>(points.size());
  Eigen::MatrixXd count = Eigen::MatrixXd::Zero(n, frames), sum2 = count;
  std::vector<std::vector<Eigen::Vector3d>> sum(
      points.size(), std::vector<Eigen::Vector3d>(static_cast<std::size_t>(frames), Eigen::Vector3d::Zero()));
  Tracker tracker(model, session.mapping, session.tracker, head.rate_hz, samples);
  MarkerFrame frame;
  long tracked = 0;
  for (Eigen::Index f = 0; f < head.frame_count(); ++f) {
    head.read_frame(f, frame);
    const FrameEstimate& estimate = tracker.process(frame.positions, frame.visible);
    if (!estimate.tracked || tracked++ < options.skip_frames) continue;
    const body::FrameTransforms transforms =
        body::joint_frames(model, estimate.pose.root_position, estimate.root_rotation, estimate.pose.joints);
    for (Eigen::Index i = 0; i < n; ++i) {
      const int p = points[static_cast<std::size_t>(i)];
      if (!frame.visible(p)) continue;
      for (int k = 0; k < frames; ++k) {
        const auto kk = static_cast<std::size_t>(k);
        const Eigen::Vector3d local =
            transforms.rotations[kk].transpose() * (frame.positions.col(p) - transforms.origins[kk]);
        sum[static_cast<std::size_t>(i)][kk] += local;
        sum2(i, k) += local.squaredNorm();
        count(i, k) += 1;
      }
    }
  }
  FrameSpread result;
  result.spread.setConstant(n, frames, std::numeric_limits<double>::infinity());
  result.mean = sum;
  for (Eigen::Index i = 0; i < n; ++i)
    for (int k = 0; k < frames; ++k)
      if (count(i, k) >= 10) {
        const Eigen::Vector3d mean =
            sum[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)] / count(i, k);
        result.mean[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)] = mean;
        result.spread(i, k) = std::sqrt(std::max(0.0, sum2(i, k) / count(i, k) - mean.squaredNorm()));
      }
  return result;
}

}  // namespace detail

/// Infers a marker set for `recording` (labels as recorded; points with empty labels, model
/// outputs, are left out). Throws std::invalid_argument with one sentence when the recording
/// cannot be labelled unambiguously: too few markers or frames, one rigid cluster, no clear facing
/// direction, or markers that ride rigidly on no segment.
inline InferredMarkerSet infer_marker_set(const MarkerSequence& recording, const SampleSet& samples,
                                          const MarkerSetInferenceOptions& options = {}) {
  const body::BodyModel base = body::mmm_body_model(1000);
  std::vector<int> points;
  std::map<std::string, int> seen;
  for (std::size_t p = 0; p < recording.labels.size(); ++p) {
    const std::string& label = recording.labels[p];
    if (label.empty() || !recording.visible.row(static_cast<Eigen::Index>(p)).any()) continue;
    if (!seen.emplace(upper_case(label), static_cast<int>(p)).second)
      throw std::invalid_argument("the label " + label +
                                  " names two points; a marker set needs one label per marker");
    points.push_back(static_cast<int>(p));
  }
  if (points.size() < 8)
    throw std::invalid_argument(
        "only " + std::to_string(points.size()) +
        " labelled points are ever seen; at least 8 are needed to infer a marker set");
  if (recording.frame_count() < 2 * options.skip_frames + 10)
    throw std::invalid_argument("the recording has " + std::to_string(recording.frame_count()) +
                                " frames; at least " + std::to_string(2 * options.skip_frames + 10) +
                                " are needed to infer a marker set");

  InferredMarkerSet result;
  result.clusters = find_rigid_clusters(recording, points, options.clusters);
  if (result.clusters.clusters.size() < 2)
    throw std::invalid_argument("all " + std::to_string(points.size()) +
                                " markers keep their mutual distances (one rigid cluster): nothing moves "
                                "against anything else, so no segment can be told from another");

  // The template frame: the first that shows the most markers.
  long template_frame = 0;
  long most = -1;
  for (Eigen::Index f = 0; f < recording.frame_count(); ++f) {
    long visible = 0;
    for (int p : points) visible += recording.visible(p, f) ? 1 : 0;
    if (visible > most) most = visible, template_frame = static_cast<long>(f);
  }
  result.template_frame = template_frame;
  std::vector<int> shown;
  for (int p : points)
    if (recording.visible(p, template_frame)) shown.push_back(p);
  Eigen::Matrix3Xd lab(3, static_cast<Eigen::Index>(shown.size()));
  for (std::size_t i = 0; i < shown.size(); ++i)
    lab.col(static_cast<Eigen::Index>(i)) = recording.frame(template_frame).col(shown[i]);
  const Eigen::Vector3d extent = lab.rowwise().maxCoeff() - lab.rowwise().minCoeff();
  int up = options.up_axis;
  if (up < 0) extent.maxCoeff(&up);
  if (up > 2) throw std::invalid_argument("the vertical axis must be 0 (x), 1 (y) or 2 (z)");
  result.up_axis = up;

  // Template fit: height, arm abduction and heading on grids, the translation by a few steps of
  // nearest-point matching; the cost is robust (a residual counts at most 150 mm).
  const std::vector<detail::TemplatePoint> candidates = detail::template_points(base, options.known_sets);
  constexpr double kCap = 150.0;
  struct Fit {
    double cost = std::numeric_limits<double>::infinity();
    double height = 0, heading = 0, abduction = 0;
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
    std::vector<int> nearest;
  };
  constexpr int kHeadings = 36;
  std::vector<Fit> best_by_heading(kHeadings);
  for (const double abduction : {0.0, 0.4, 0.8, 1.2, 1.57}) {
    const body::FrameTransforms zero = body::joint_frames(
        base, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), detail::arms_out(base, abduction));
    Eigen::Matrix3Xd model(3, static_cast<Eigen::Index>(candidates.size()));
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const auto k = static_cast<std::size_t>(candidates[c].frame);
      model.col(static_cast<Eigen::Index>(c)) = zero.origins[k] + zero.rotations[k] * candidates[c].offset;
    }
    for (double height = 1300; height <= 2100; height += 50) {
      const Eigen::Matrix3Xd scaled = model * (height / 1000.0);
      for (int h = 0; h < kHeadings; ++h) {
        const double heading = 2 * kPi * h / kHeadings;
        const Eigen::Matrix3d rotation = detail::lab_from_model(up, heading);
        const Eigen::Matrix3Xd placed = rotation * scaled;
        Eigen::Vector3d translation = lab.rowwise().mean() - placed.rowwise().mean();
        translation(up) = lab.row(up).minCoeff() - placed.row(up).minCoeff();
        Fit fit;
        fit.height = height, fit.heading = heading, fit.abduction = abduction;
        fit.nearest.assign(shown.size(), 0);
        for (int step = 0; step < 4; ++step) {
          double cost = 0;
          Eigen::Vector3d shift = Eigen::Vector3d::Zero();
          int inliers = 0;
          for (Eigen::Index i = 0; i < lab.cols(); ++i) {
            Eigen::Index nearest = 0;
            const double d2 =
                (placed.colwise() - (lab.col(i) - translation)).colwise().squaredNorm().minCoeff(&nearest);
            fit.nearest[static_cast<std::size_t>(i)] = static_cast<int>(nearest);
            cost += std::min(d2, kCap * kCap);
            if (d2 < kCap * kCap) shift += lab.col(i) - (placed.col(nearest) + translation), ++inliers;
          }
          fit.cost = cost, fit.translation = translation;
          if (inliers > 0) translation += shift / inliers;
        }
        if (fit.cost < best_by_heading[static_cast<std::size_t>(h)].cost)
          best_by_heading[static_cast<std::size_t>(h)] = fit;
      }
    }
  }
  int best = 0;
  for (int h = 1; h < kHeadings; ++h)
    if (best_by_heading[static_cast<std::size_t>(h)].cost <
        best_by_heading[static_cast<std::size_t>(best)].cost)
      best = h;
  const Fit& fit = best_by_heading[static_cast<std::size_t>(best)];
  double rival = std::numeric_limits<double>::infinity();
  for (int h = 0; h < kHeadings; ++h) {
    const int apart = std::min((h - best + kHeadings) % kHeadings, (best - h + kHeadings) % kHeadings);
    if (apart * 360 / kHeadings > 60)
      rival = std::min(rival, best_by_heading[static_cast<std::size_t>(h)].cost);
  }
  if (!(rival > options.heading_margin * fit.cost)) {
    std::ostringstream s;
    s << "the subject's facing direction in frame " << template_frame
      << " is ambiguous (the best fit of the body model is only " << std::lround(100 * (rival / fit.cost - 1))
      << " % better than one facing "
      << "more than 60 degrees away); give a marker set (--markerset)";
    throw std::invalid_argument(s.str());
  }

  // The initial set: every marker on the frame of its nearest template point. A marker's offset on
  // any frame is where the template pose puts it: the standing subject defines the zero of the
  // joint angles, as the model's zero pose does (offsets measured from tracked frames would carry
  // the first rounds' errors into the set).
  const body::FrameTransforms template_frames = body::joint_frames(
      base, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), detail::arms_out(base, fit.abduction));
  const Eigen::Matrix3d rotation = detail::lab_from_model(up, fit.heading);
  std::vector<std::optional<Eigen::Vector3d>> standing(points.size());  // model coordinates, 1000 mm
  std::vector<int> frame_of(points.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto at = std::find(shown.begin(), shown.end(), points[i]);
    if (at == shown.end()) continue;
    const auto column = at - shown.begin();
    frame_of[i] = candidates[static_cast<std::size_t>(fit.nearest[static_cast<std::size_t>(column)])].frame;
    standing[i] =
        Eigen::Vector3d(rotation.transpose() * (lab.col(column) - fit.translation) * (1000.0 / fit.height));
  }
  body::MarkerSet set;
  set.name = "inferred";
  set.reference_height_mm = 1000.0;
  const auto place = [&](std::size_t i, const Eigen::Vector3d& fallback) {
    const auto k = static_cast<std::size_t>(frame_of[i]);
    set.entries[i].frame = body::marker_set_frame_name(base, frame_of[i]);
    set.entries[i].offset = standing[i] ? Eigen::Vector3d(template_frames.rotations[k].transpose() *
                                                          (*standing[i] - template_frames.origins[k]))
                                        : fallback;
  };
  for (std::size_t i = 0; i < points.size(); ++i) {
    set.entries.emplace_back();
    set.entries[i].label = recording.labels[static_cast<std::size_t>(points[i])];
    place(i, Eigen::Vector3d::Zero());
  }
  std::ostringstream fitted;
  fitted << "template fit in frame " << template_frame << ": "
         << "xyz"[up] << " up, height " << std::lround(fit.height) << " mm, arms out "
         << std::lround(fit.abduction * 180 / kPi) << " deg, facing " << std::lround(fit.heading * 180 / kPi)
         << " deg (the next direction more than 60 deg away costs "
         << std::lround(100 * (rival / fit.cost - 1)) << " % more)";
  result.notes.push_back(fitted.str());

  // Rounds of tracking and reassignment. A marker moves only to a neighbouring segment (its parent
  // or a child): the template fit placed it near its segment, and a distant segment can look
  // rigid with it only where the tracking of both failed.
  std::map<std::string, std::string> parent_segment;
  for (const body::Joint& joint : base.joints)
    parent_segment.emplace(joint.group, body::segment_of_frame(base, joint.parent_frame));
  const auto neighbours = [&](int a, int b) {
    const std::string sa = body::segment_of_frame(base, a), sb = body::segment_of_frame(base, b);
    return sa == sb || parent_segment[sa] == sb || parent_segment[sb] == sa;
  };
  double height = fit.height;
  detail::FrameSpread spread;
  for (int round = 0; round < options.max_rounds; ++round) {
    double estimated = height;
    spread = detail::track_and_measure(recording, points, set, round == 0 ? height : 0.0, samples, options,
                                       estimated);
    height = estimated;
    int moved = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto row = static_cast<Eigen::Index>(i);
      int best_frame = frame_of[i];
      double best_spread = std::numeric_limits<double>::infinity();
      for (int k = 0; k < base.frame_count(); ++k)
        if (neighbours(frame_of[i], k) && spread.spread(row, k) < best_spread)
          best_frame = k, best_spread = spread.spread(row, k);
      if (!std::isfinite(best_spread)) continue;
      const double own = spread.spread(row, frame_of[i]);
      if (std::isfinite(own) && (own < options.rigid_spread_mm || !(best_spread < options.move_ratio * own)))
        best_frame = frame_of[i];
      if (best_frame == frame_of[i]) continue;
      ++moved;
      frame_of[i] = best_frame;
      place(i, spread.mean[i][static_cast<std::size_t>(best_frame)] * (1000.0 / height));
    }
    result.rounds = round + 1;
    if (moved == 0) break;
  }
  result.height_mm = height;

  // Confidence per marker and segment.
  std::map<std::string, InferredSegment> by_segment;
  double total2 = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    const std::string segment = body::segment_of_frame(base, frame_of[i]);
    const double own = spread.spread(row, frame_of[i]);
    double other = std::numeric_limits<double>::infinity();
    for (int k = 0; k < base.frame_count(); ++k)
      if (body::segment_of_frame(base, k) != segment) other = std::min(other, spread.spread(row, k));
    InferredSegment& s = by_segment[segment];
    s.segment = segment;
    ++s.markers;
    const double o = std::isfinite(own) ? own : options.max_spread_mm * 10;
    s.spread_mm += o * o;
    s.confidence += std::isfinite(other) && std::isfinite(own) ? std::max(0.0, 1.0 - own / other) : 0.0;
    total2 += o * o;
  }
  result.spread_mm = std::sqrt(total2 / static_cast<double>(points.size()));
  for (int k = 0; k < base.frame_count(); ++k) {
    const auto found = by_segment.find(body::segment_of_frame(base, k));
    if (found == by_segment.end() || found->second.markers == 0) continue;
    InferredSegment s = found->second;
    s.spread_mm = std::sqrt(s.spread_mm / s.markers);
    s.confidence /= s.markers;
    result.segments.push_back(s);
    found->second.markers = 0;  // listed once
  }
  if (!(result.spread_mm <= options.max_spread_mm)) {
    std::ostringstream s;
    s << "the markers ride rigidly on no segment of the body model (RMS spread "
      << std::lround(result.spread_mm) << " mm on their best segments after " << result.rounds
      << " rounds of tracking); give a marker set (--markerset)";
    throw std::invalid_argument(s.str());
  }

  std::ostringstream description;
  description << "Inferred by s2kf from the recording's motion (" << result.clusters.clusters.size()
              << " rigid clusters; " << fitted.str() << "; " << result.rounds
              << " round(s) of tracking and reassignment). Segment, markers, confidence:";
  for (const InferredSegment& s : result.segments)
    description << " " << s.segment << " " << s.markers << " " << std::lround(100 * s.confidence) << " %;";
  description << " check the frames and correct them by hand where the confidence is low.";
  set.description = description.str();
  result.set = set;
  return result;
}

}  // namespace s2kf::track
