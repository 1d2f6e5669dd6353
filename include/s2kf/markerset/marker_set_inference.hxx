/// @file
/// The definitions of <s2kf/markerset/marker_set_inference.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/markerset/marker_set_inference.hpp>

#include <s2kf/geometry/nearest_point_tree.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/tracker.hpp>

namespace s2kf::markerset {
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

/// The template fit in one frame: the facing direction, height, pose and translation of the model
/// that put its template points nearest the markers, and which template point each shown marker
/// is nearest to.
struct TemplateFit {
  double cost = std::numeric_limits<double>::infinity();  ///< sum of capped squared residuals (mm^2)
  double height = 0, heading = 0;
  Eigen::VectorXd joints;  ///< the fitted pose (zero but for the arms, legs and trunk refined)
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  std::vector<int> nearest;         ///< per shown marker, its template point
  std::vector<double> residual_mm;  ///< per shown marker, its distance to that point
  /// The cost of the best fit facing more than 60 degrees away, over `cost`: how clearly the
  /// facing direction won (above 1: it did).
  double margin = 0;
  bool pose_refined = false;  ///< whether the zero pose fitted too poorly and the pose was refined
  double rms_mm() const {
    return std::sqrt(cost / static_cast<double>(std::max<std::size_t>(1, nearest.size())));
  }
};

/// The template points of the 1000 mm model at `joints`, in the model's own frame (translation
/// zero, not turned).
inline Eigen::Matrix3Xd template_in_pose(const body::BodyModel& base,
                                         const std::vector<TemplatePoint>& candidates,
                                         const Eigen::VectorXd& joints) {
  const body::FrameTransforms frames =
      body::joint_frames(base, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), joints);
  Eigen::Matrix3Xd points(3, static_cast<Eigen::Index>(candidates.size()));
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const auto k = static_cast<std::size_t>(candidates[c].frame);
    points.col(static_cast<Eigen::Index>(c)) = frames.origins[k] + frames.rotations[k] * candidates[c].offset;
  }
  return points;
}

/// A residual counts at most this much in the template cost: a marker far from every template
/// point (a virtual point, a stray) must not pull the fit.
inline constexpr double kTemplateCap = 150.0;

/// The matching steps: in each, every marker's nearest placed template point (`nearest(marker)`,
/// the marker relative to fit.translation: its index and squared distance; index -1 where none is
/// within the cap), the capped cost, and the translation moved by the mean residual of the markers
/// within the cap. Sets cost, translation, nearest and residual_mm (of the last step).
template <class Placed, class Nearest>
void match_steps(const Placed& placed, const Eigen::Matrix3Xd& lab, int steps, const Nearest& nearest,
                 TemplateFit& fit) {
  fit.nearest.assign(static_cast<std::size_t>(lab.cols()), -1);
  fit.residual_mm.assign(static_cast<std::size_t>(lab.cols()), std::numeric_limits<double>::infinity());
  for (int step = 0; step < steps; ++step) {
    double cost = 0;
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();
    int inliers = 0;
    for (Eigen::Index i = 0; i < lab.cols(); ++i) {
      const geometry::NearestPointTree::Hit hit = nearest(Eigen::Vector3d(lab.col(i) - fit.translation));
      fit.nearest[static_cast<std::size_t>(i)] = static_cast<int>(hit.index);
      fit.residual_mm[static_cast<std::size_t>(i)] = std::sqrt(hit.squared_distance);
      cost += std::min(hit.squared_distance, kTemplateCap * kTemplateCap);
      if (hit.squared_distance < kTemplateCap * kTemplateCap)
        shift += lab.col(i) - (placed.col(hit.index) + fit.translation), ++inliers;
    }
    fit.cost = cost;
    if (step + 1 < steps && inliers > 0) fit.translation += shift / inliers;
  }
}

/// The cost of `fit` (its height, heading, joints) with the translation refined by `steps`
/// nearest-point matching steps from fit.translation, each marker compared with every template
/// point; sets cost, translation, nearest, residual_mm.
inline void match_template(const body::BodyModel& base, const std::vector<TemplatePoint>& candidates,
                           const Eigen::Matrix3Xd& lab, int up, int steps, TemplateFit& fit) {
  // One row per coordinate, so that the distances to every template point are computed a vector
  // of points at a time.
  const Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor> placed =
      lab_from_model(up, fit.heading) * template_in_pose(base, candidates, fit.joints) *
      (fit.height / 1000.0);
  Eigen::Array<double, 1, Eigen::Dynamic> squared_distance(placed.cols());
  const auto scan = [&](const Eigen::Vector3d& marker) {
    squared_distance = (placed.row(0).array() - marker.x()).square() +
                       (placed.row(1).array() - marker.y()).square() +
                       (placed.row(2).array() - marker.z()).square();
    geometry::NearestPointTree::Hit hit;
    hit.squared_distance = squared_distance.minCoeff(&hit.index);
    return hit;
  };
  match_steps(placed, lab, steps, scan, fit);
}

/// Lets the pose vary where the markers ask for it: pattern search over the hips, knees,
/// shoulders, elbows and trunk (steps of 0.4 rad halved to 0.05, within the joints' limits), the
/// translation refined after each step. A subject mid-stride, crouching or with the hands in front
/// then fits as well as one standing, and the offsets read from the fit are right for its pose.
inline void refine_pose(const body::BodyModel& base, const std::vector<TemplatePoint>& candidates,
                        const Eigen::Matrix3Xd& lab, int up, TemplateFit& fit) {
  std::vector<int> free;
  for (const char* name : {"BTx", "LHx", "LHy", "LKx", "RHx", "RHy", "RKx", "LSx", "LSy", "LSz", "LEx", "RSx",
                           "RSy", "RSz", "REx"})
    free.push_back(base.joint_index(name));
  for (double step = 0.4; step >= 0.05; step /= 2) {
    bool improved = true;
    for (int pass = 0; pass < 3 && improved; ++pass) {
      improved = false;
      for (int j : free)
        for (const double sign : {1.0, -1.0}) {
          TemplateFit trial = fit;
          const body::Joint& joint = base.joints[static_cast<std::size_t>(j)];
          trial.joints(j) = std::clamp(fit.joints(j) + sign * step, joint.lower, joint.upper);
          if (trial.joints(j) == fit.joints(j)) continue;
          match_template(base, candidates, lab, up, 2, trial);
          if (trial.cost < fit.cost) fit = std::move(trial), improved = true;
        }
    }
  }
}

/// Fits the model, scaled to 1300-2100 mm and turned about the vertical `up` in 10 deg steps, at
/// its zero pose with the arms turned out 0-90 deg, to the marker positions `lab` by nearest
/// points, the translation refined by four matching steps; where the best of these leaves an RMS
/// residual above `refine_above_rms_mm`, lets the pose vary (refine_pose) for the best direction
/// and its best rivals; compares the best direction with the best more than 60 deg away. Where the
/// near-zero pose fits, it is kept: refining it only trades a marker at a joint between the two
/// segments that meet there.
inline TemplateFit fit_template(const body::BodyModel& base, const std::vector<TemplatePoint>& candidates,
                                const Eigen::Matrix3Xd& lab, int up, double refine_above_rms_mm) {
  constexpr int kHeadings = 36;
  std::vector<TemplateFit> best_by_heading(kHeadings);
  std::vector<Eigen::Vector3d> start_by_heading(kHeadings, Eigen::Vector3d::Zero());
  for (const double abduction : {0.0, 0.4, 0.8, 1.2, 1.57}) {
    const Eigen::VectorXd joints = arms_out(base, abduction);
    // A trial placement turns and scales these; the nearest point to a marker is found by taking
    // the marker back into the model's frame instead, in a tree built once per pose.
    const Eigen::Matrix3Xd model_points = template_in_pose(base, candidates, joints);
    const geometry::NearestPointTree tree(model_points);
    for (double height = 1300; height <= 2100; height += 50)
      for (int h = 0; h < kHeadings; ++h) {
        TemplateFit fit;
        fit.height = height, fit.heading = 2 * kPi * h / kHeadings;
        const Eigen::Matrix3d rotation = lab_from_model(up, fit.heading);
        const Eigen::Matrix3Xd placed = rotation * model_points * (height / 1000.0);
        // Start at the markers' centroid, feet on the lowest marker; the matching steps shift it.
        fit.translation = lab.rowwise().mean() - placed.rowwise().mean();
        fit.translation(up) = lab.row(up).minCoeff() - placed.row(up).minCoeff();
        const Eigen::Vector3d start = fit.translation;
        const double scale = height / 1000.0, cap_in_model = kTemplateCap / scale;
        const auto search = [&](const Eigen::Vector3d& marker) {
          geometry::NearestPointTree::Hit hit =
              tree.nearest(rotation.transpose() * marker / scale, cap_in_model * cap_in_model);
          if (hit.index >= 0) hit.squared_distance = (placed.col(hit.index) - marker).squaredNorm();
          return hit;
        };
        match_steps(placed, lab, 4, search, fit);
        if (fit.cost < best_by_heading[static_cast<std::size_t>(h)].cost) {
          fit.joints = joints;
          best_by_heading[static_cast<std::size_t>(h)] = std::move(fit);
          start_by_heading[static_cast<std::size_t>(h)] = start;
        }
      }
  }
  // Each direction's best placement again, by comparing every marker with every point: the
  // nearest point of the markers beyond the cap, too.
  for (int h = 0; h < kHeadings; ++h) {
    TemplateFit& fit = best_by_heading[static_cast<std::size_t>(h)];
    fit.translation = start_by_heading[static_cast<std::size_t>(h)];
    match_template(base, candidates, lab, up, 4, fit);
  }
  // Refined: the best direction, the best more than 60 deg from it and the best more than 120 deg
  // from it (facing backwards); the margin compares refined fits only.
  const auto apart = [](double a, double b) { return std::abs(std::remainder(a - b, 2 * kPi)); };
  const auto best_beyond = [&](double from, double angle) {
    int best = -1;
    for (int h = 0; h < kHeadings; ++h)
      if (apart(2 * kPi * h / kHeadings, from) > angle + 1e-9 &&
          (best < 0 || best_by_heading[static_cast<std::size_t>(h)].cost <
                           best_by_heading[static_cast<std::size_t>(best)].cost))
        best = h;
    return best_by_heading[static_cast<std::size_t>(best)];
  };
  std::vector<TemplateFit> refined{best_beyond(0, -1)};
  refined.push_back(best_beyond(refined[0].heading, kPi / 3));
  refined.push_back(best_beyond(refined[0].heading, 2 * kPi / 3));
  if (refined[0].rms_mm() > refine_above_rms_mm)
    for (TemplateFit& r : refined) refine_pose(base, candidates, lab, up, r), r.pose_refined = true;
  std::size_t best = 0;
  for (std::size_t r = 1; r < refined.size(); ++r)
    if (refined[r].cost < refined[best].cost) best = r;
  TemplateFit fit = refined[best];
  double rival = std::numeric_limits<double>::infinity();
  for (const TemplateFit& r : refined)
    if (apart(r.heading, fit.heading) > kPi / 3 + 1e-9) rival = std::min(rival, r.cost);
  fit.margin = rival / fit.cost;
  return fit;
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
  pipeline::SessionOptions session_options;
  session_options.tracker = options.tracker;
  session_options.calibrate = false;
  session_options.height_mm = height_mm;
  const pipeline::Session session = pipeline::prepare_session(source, set, session_options, samples);
  estimated_height_mm = session.height_mm;
  const body::BodyModel& model = session.model;
  const int frames = model.frame_count();
  const auto n = static_cast<Eigen::Index>(points.size());
  Eigen::MatrixXd count = Eigen::MatrixXd::Zero(n, frames), sum2 = count;
  std::vector<std::vector<Eigen::Vector3d>> sum(
      points.size(), std::vector<Eigen::Vector3d>(static_cast<std::size_t>(frames), Eigen::Vector3d::Zero()));
  track::Tracker tracker(model, session.mapping, session.tracker, head.rate_hz, samples);
  MarkerFrame frame;
  long tracked = 0;
  for (Eigen::Index f = 0; f < head.frame_count(); ++f) {
    head.read_frame(f, frame);
    const track::FrameEstimate& estimate = tracker.process(frame.positions, frame.visible);
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

S2KF_INLINE InferredMarkerSet infer_marker_set(const MarkerSequence& recording, const SampleSet& samples,
                                               const MarkerSetInferenceOptions& options) {
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

  // Candidate template frames: up to options.template_frames, spread evenly over the frames that
  // show the most markers (a marker the template frame does not show is placed from the motion
  // alone, less surely).
  std::vector<long> visible_count(static_cast<std::size_t>(recording.frame_count()), 0);
  long most = 0;
  for (Eigen::Index f = 0; f < recording.frame_count(); ++f) {
    for (int p : points) visible_count[static_cast<std::size_t>(f)] += recording.visible(p, f) ? 1 : 0;
    most = std::max(most, visible_count[static_cast<std::size_t>(f)]);
  }
  std::vector<long> well_seen;
  for (std::size_t f = 0; f < visible_count.size(); ++f)
    if (visible_count[f] == most) well_seen.push_back(static_cast<long>(f));
  const long wanted = std::max(1, options.template_frames);
  std::vector<long> template_candidates;
  for (long k = 0; k < std::min<long>(wanted, static_cast<long>(well_seen.size())); ++k)
    template_candidates.push_back(
        well_seen[static_cast<std::size_t>(k * static_cast<long>(well_seen.size()) / wanted)]);
  const auto shown_in = [&](long f) {
    std::vector<int> shown;
    for (int p : points)
      if (recording.visible(p, f)) shown.push_back(p);
    return shown;
  };
  const auto positions = [&](long f, const std::vector<int>& shown) {
    Eigen::Matrix3Xd lab(3, static_cast<Eigen::Index>(shown.size()));
    for (std::size_t i = 0; i < shown.size(); ++i)
      lab.col(static_cast<Eigen::Index>(i)) = recording.frame(f).col(shown[i]);
    return lab;
  };
  // The vertical: the axis along which the candidate frames' markers spread furthest (a subject
  // is taller than wide in most frames, whatever it does in a few).
  int up = options.up_axis;
  if (up < 0) {
    Eigen::Vector3d extent = Eigen::Vector3d::Zero();
    for (long f : template_candidates) {
      const Eigen::Matrix3Xd lab = positions(f, shown_in(f));
      extent += lab.rowwise().maxCoeff() - lab.rowwise().minCoeff();
    }
    extent.maxCoeff(&up);
  }
  if (up > 2) throw std::invalid_argument("the vertical axis must be 0 (x), 1 (y) or 2 (z)");
  result.up_axis = up;

  // The template fit in every candidate frame. Shortlisted: the frames whose facing direction wins
  // clearly (beyond options.heading_margin), those where the zero pose fitted first (the subject
  // stands there, and the standing subject defines the zero of the joint angles, as the model's
  // zero pose does), then the clearest; each is tried through the rounds below, and the one whose
  // markers then ride most rigidly on their segments is kept.
  const std::vector<detail::TemplatePoint> candidates = detail::template_points(base, options.known_sets);
  std::vector<std::pair<long, detail::TemplateFit>> clear;
  std::string excluded_note;
  double best_margin = 0;
  long best_margin_frame = template_candidates.front();
  for (long f : template_candidates) {
    detail::TemplateFit trial = detail::fit_template(base, candidates, positions(f, shown_in(f)), up,
                                                     options.refine_pose_above_rms_mm);
    if (trial.margin > best_margin) best_margin = trial.margin, best_margin_frame = f;
    if (trial.margin > options.heading_margin) clear.emplace_back(f, std::move(trial));
  }
  if (clear.empty()) {
    std::ostringstream s;
    s << "the subject's facing direction is ambiguous in all " << template_candidates.size()
      << " well-seen frames tried (the best fit of the body model, in frame " << best_margin_frame
      << ", is only " << std::lround(100 * (best_margin - 1))
      << " % better than one facing more than 60 degrees away); give a marker set (--markerset)";
    throw std::invalid_argument(s.str());
  }
  std::stable_sort(clear.begin(), clear.end(), [](const auto& a, const auto& b) {
    if (a.second.pose_refined != b.second.pose_refined) return b.second.pose_refined;
    return a.second.margin > b.second.margin;
  });
  if (!clear.front().second.pose_refined)
    clear.erase(
        std::remove_if(clear.begin(), clear.end(), [](const auto& c) { return c.second.pose_refined; }),
        clear.end());
  clear.resize(
      std::min<std::size_t>(clear.size(), static_cast<std::size_t>(std::max(1, options.template_attempts))));

  // Points far from every template point (beyond the cost's cap) in most of the shortlisted fits
  // are no markers on the skin: a lab's virtual points (segment origins and axes written as
  // points), a stray. They are left out of the set.
  {
    std::map<int, int> far, shown_count;
    for (const auto& [frame, fit] : clear) {
      const std::vector<int> shown = shown_in(frame);
      for (std::size_t c = 0; c < shown.size(); ++c) {
        ++shown_count[shown[c]];
        if (fit.residual_mm[c] > detail::kTemplateCap) ++far[shown[c]];
      }
    }
    std::vector<int> kept_points;
    std::vector<std::string> left_out;
    for (int p : points)
      if (2 * far[p] > shown_count[p])
        left_out.push_back(recording.labels[static_cast<std::size_t>(p)]);
      else
        kept_points.push_back(p);
    if (!left_out.empty()) {
      if (kept_points.size() < 8)
        throw std::invalid_argument(
            "only " + std::to_string(kept_points.size()) +
            " points lie near the body model's surface in the template fit; at least 8 "
            "are needed to infer a marker set");
      std::ostringstream s;
      s << "left out " << left_out.size() << " points far (over " << std::lround(detail::kTemplateCap)
        << " mm) from the body's surface in the template fit, no markers on the skin:";
      for (std::size_t k = 0; k < left_out.size(); ++k)
        s << (k < 12 ? " " + left_out[k] : k == 12 ? " ..." : "");
      excluded_note = s.str();
      points = kept_points;
      for (auto& [frame, fit] : clear)
        detail::match_template(base, candidates, positions(frame, shown_in(frame)), up, 1, fit);
    }
  }

  std::map<std::string, std::string> parent_segment;
  for (const body::Joint& joint : base.joints)
    parent_segment.emplace(joint.group, body::segment_of_frame(base, joint.parent_frame));
  const auto neighbours = [&](int a, int b) {
    const std::string sa = body::segment_of_frame(base, a), sb = body::segment_of_frame(base, b);
    return sa == sb || parent_segment[sa] == sb || parent_segment[sb] == sa;
  };

  /// A set grown from one template fit: its frames, the rounds' last spreads, and what was done.
  struct Attempt {
    long template_frame = 0;
    std::vector<int> frame_of;
    body::MarkerSet set;
    detail::FrameSpread spread;
    double height = 0;
    int rounds = 0;
    double spread_rms_mm = std::numeric_limits<double>::infinity();  ///< over markers on their frames
    std::vector<std::string> notes;
  };
  const auto attempt = [&](long template_frame, const detail::TemplateFit& fit) {
    Attempt a;
    a.template_frame = template_frame;
    const std::vector<int> shown = shown_in(template_frame);
    const Eigen::Matrix3Xd lab = positions(template_frame, shown);

    // The initial set: every marker on the frame of its nearest template point. A marker's offset
    // on any frame is where the fitted pose puts it: the standing subject defines the zero of
    // the joint angles, as the model's zero pose does (offsets measured from tracked frames would
    // carry the first rounds' errors into the set).
    const body::FrameTransforms template_frames =
        body::joint_frames(base, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), fit.joints);
    const Eigen::Matrix3d rotation = detail::lab_from_model(up, fit.heading);
    std::vector<std::optional<Eigen::Vector3d>> standing(points.size());  // model coordinates, 1000 mm
    std::vector<int>& frame_of = a.frame_of;
    frame_of.assign(points.size(), 0);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto at = std::find(shown.begin(), shown.end(), points[i]);
      if (at == shown.end()) continue;
      const auto column = at - shown.begin();
      frame_of[i] = candidates[static_cast<std::size_t>(fit.nearest[static_cast<std::size_t>(column)])].frame;
      standing[i] =
          Eigen::Vector3d(rotation.transpose() * (lab.col(column) - fit.translation) * (1000.0 / fit.height));
    }
    Eigen::Index largest = 0;
    std::ostringstream fitted;
    fitted << "template fit in frame " << template_frame << " (" << template_candidates.size()
           << " well-seen frames fitted, " << clear.size() << " tried): "
           << "xyz"[up] << " up, height " << std::lround(fit.height) << " mm, largest joint angle "
           << std::lround(fit.joints.cwiseAbs().maxCoeff(&largest) * 180 / kPi) << " deg ("
           << base.joints[static_cast<std::size_t>(largest)].name << "), facing "
           << std::lround(fit.heading * 180 / kPi) << " deg (the next direction more than 60 deg away costs "
           << std::lround(100 * (fit.margin - 1)) << " % more), RMS residual " << std::lround(fit.rms_mm())
           << " mm";
    a.notes.push_back(fitted.str());
    if (!excluded_note.empty()) a.notes.push_back(excluded_note);

    // The topology check (segment_rigidity.hpp): a marker whose distances to its segment's
    // markers vary by centimetres but stay constant to another segment's moves there (the template
    // put a thigh marker on the hand hanging beside it). Markers the template frame does not show
    // go to the segment whose markers keep the steadiest distances to them.
    std::vector<int> placed_points, placed_frames;
    std::vector<std::size_t> placed_index;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (standing[i])
        placed_points.push_back(points[i]), placed_frames.push_back(frame_of[i]), placed_index.push_back(i);
    for (const SegmentMove& move :
         repair_segment_assignment(result.clusters, base, placed_points, placed_frames, options.rigidity)) {
      std::ostringstream s;
      s << "moved " << recording.labels[static_cast<std::size_t>(placed_points[move.marker])] << " from "
        << move.from << " to " << move.to << ": its distances to the markers of " << move.from << " vary by "
        << std::lround(move.from_sd_mm) << " mm (median SD), to those of " << move.to << " by "
        << std::lround(move.to_sd_mm) << " mm";
      a.notes.push_back(s.str());
    }
    for (std::size_t j = 0; j < placed_index.size(); ++j) frame_of[placed_index[j]] = placed_frames[j];
    const auto placed_by_segment = points_by_segment(base, placed_points, placed_frames);
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (standing[i]) continue;
      double steadiest = std::numeric_limits<double>::infinity();
      for (const auto& [segment, members] : placed_by_segment) {
        const double sd = median_distance_sd(result.clusters, points[i], members);
        if (!(sd < steadiest)) continue;
        steadiest = sd;
        for (std::size_t j = 0; j < placed_points.size(); ++j)
          if (body::segment_of_frame(base, placed_frames[j]) == segment) frame_of[i] = placed_frames[j];
      }
    }

    body::MarkerSet& set = a.set;
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

    // Rounds of tracking and reassignment. A marker moves only to a neighbouring segment (its
    // parent or a child): the template fit and the topology check placed it near its segment, and
    // a distant segment can look rigid with it only where the tracking of both failed. A marker
    // the template frame does not show takes its mean position on its frame over the tracked frames.
    a.height = fit.height;
    for (int round = 0; round < options.max_rounds; ++round) {
      double estimated = a.height;
      a.spread = detail::track_and_measure(recording, points, set, round == 0 ? a.height : 0.0, samples,
                                           options, estimated);
      a.height = estimated;
      int moved = 0;
      for (std::size_t i = 0; i < points.size(); ++i) {
        const auto row = static_cast<Eigen::Index>(i);
        int best_frame = frame_of[i];
        double best_spread = std::numeric_limits<double>::infinity();
        for (int k = 0; k < base.frame_count(); ++k)
          if (neighbours(frame_of[i], k) && a.spread.spread(row, k) < best_spread)
            best_frame = k, best_spread = a.spread.spread(row, k);
        if (!std::isfinite(best_spread)) continue;
        const double own = a.spread.spread(row, frame_of[i]);
        if (std::isfinite(own) &&
            (own < options.rigid_spread_mm || !(best_spread < options.move_ratio * own)))
          best_frame = frame_of[i];
        if (best_frame == frame_of[i]) {
          if (!standing[i] && std::isfinite(own))
            place(i, a.spread.mean[i][static_cast<std::size_t>(best_frame)] * (1000.0 / a.height));
          continue;
        }
        ++moved;
        frame_of[i] = best_frame;
        place(i, a.spread.mean[i][static_cast<std::size_t>(best_frame)] * (1000.0 / a.height));
      }
      a.rounds = round + 1;
      if (moved == 0) break;
    }
    double total2 = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double own = a.spread.spread(static_cast<Eigen::Index>(i), frame_of[i]);
      const double o = std::isfinite(own) ? own : options.max_spread_mm * 10;
      total2 += o * o;
    }
    a.spread_rms_mm = std::sqrt(total2 / static_cast<double>(points.size()));
    return a;
  };
  Attempt kept;
  for (const auto& [frame, fit] : clear) {
    Attempt a = attempt(frame, fit);
    if (a.spread_rms_mm < kept.spread_rms_mm) kept = std::move(a);
  }
  result.template_frame = kept.template_frame;
  result.rounds = kept.rounds;
  result.height_mm = kept.height;
  result.notes = kept.notes;
  const std::vector<int>& frame_of = kept.frame_of;
  const detail::FrameSpread& spread = kept.spread;
  body::MarkerSet& set = kept.set;
  const std::string fitted = kept.notes.front();

  // Confidence per marker and segment: the motion's (1 - spread on its segment / spread on the best
  // other), lowered to the topology's where that is weaker (1 - median distance SD to its
  // segment's markers / that to the best other segment's), and halved for a marker alone on its
  // segment, which no other marker can check.
  const std::vector<MarkerRigidity> rigidity = marker_rigidity(result.clusters, base, points, frame_of);
  std::map<std::string, InferredSegment> by_segment;
  double total2 = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    const std::string segment = body::segment_of_frame(base, frame_of[i]);
    const double own = spread.spread(row, frame_of[i]);
    double other = std::numeric_limits<double>::infinity();
    for (int k = 0; k < base.frame_count(); ++k)
      if (body::segment_of_frame(base, k) != segment) other = std::min(other, spread.spread(row, k));
    double confidence = std::isfinite(other) && std::isfinite(own) ? std::max(0.0, 1.0 - own / other) : 0.0;
    const MarkerRigidity& r = rigidity[i];
    if (!std::isfinite(r.own_sd_mm))
      confidence *= 0.5;
    else if (std::isfinite(r.best_other_sd_mm))
      confidence = std::min(confidence, std::max(0.0, 1.0 - r.own_sd_mm / r.best_other_sd_mm));
    InferredSegment& s = by_segment[segment];
    s.segment = segment;
    ++s.markers;
    const double o = std::isfinite(own) ? own : options.max_spread_mm * 10;
    s.spread_mm += o * o;
    s.confidence += confidence;
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
              << " rigid clusters; " << fitted << "; " << result.rounds
              << " round(s) of tracking and reassignment). Segment, markers, confidence:";
  for (const InferredSegment& s : result.segments)
    description << " " << s.segment << " " << s.markers << " " << std::lround(100 * s.confidence) << " %;";
  description << " check the frames and correct them by hand where the confidence is low.";
  set.description = description.str();
  result.set = set;
  return result;
}

}  // namespace s2kf::markerset
