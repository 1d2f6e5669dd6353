/// @file
/// The definitions of <s2kf/markerset/marker_set_inference.hpp>: inline where the library is used
/// header-only, compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/markerset/marker_set_inference.hpp>

#include <s2kf/core/parallel_for.hpp>
#include <s2kf/geometry/nearest_point_tree.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/tracker.hpp>

#include <cctype>

namespace s2kf::markerset {
namespace detail {

/// A place on the body where some lab puts a marker: its frame and where it is at the zero pose of
/// the 1000 mm model.
struct TemplatePoint {
  int frame = 0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< in its frame
  int copies = 1;  ///< how many markers of the base model and the sets are here
};

/// Appends the place of `marker`, or counts it once more where `points` holds it already (most
/// sets name their markers like the base model's): the same nearest points, found among fewer;
/// the counts keep the centroid that of every marker (centroid_weights).
inline void add_template_point(std::vector<TemplatePoint>& points, const body::Marker& marker) {
  for (TemplatePoint& point : points)
    if (point.frame == marker.frame && point.offset == marker.offset) {
      ++point.copies;
      return;
    }
  points.push_back({marker.frame, marker.offset});
}

/// Per template point, its share of the markers it stands for: placed points times these give
/// the centroid of every marker of the base model and the sets.
inline Eigen::VectorXd centroid_weights(const std::vector<TemplatePoint>& points) {
  Eigen::VectorXd weights(static_cast<Eigen::Index>(points.size()));
  double total = 0;
  for (const TemplatePoint& point : points) total += point.copies;
  for (std::size_t k = 0; k < points.size(); ++k)
    weights(static_cast<Eigen::Index>(k)) = points[k].copies / total;
  return weights;
}

inline std::vector<TemplatePoint> template_points(const body::BodyModel& base,
                                                  const std::vector<body::MarkerSet>& sets) {
  std::vector<TemplatePoint> points;
  for (const body::Marker& marker : base.markers) add_template_point(points, marker);
  for (const body::MarkerSet& set : sets)
    for (const body::Marker& marker : body::apply_marker_set(base, set).markers)
      add_template_point(points, marker);
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
/// within the cap. Sets cost, translation, nearest and residual_mm (of the last step). A last step
/// whose cost reaches `bound` stops there (cost at least `bound`, nearest and residual_mm partial):
/// the caller keeps only fits below it, and the cost's terms are never negative.
template <class Placed, class Nearest>
void match_steps(const Placed& placed, const Eigen::Matrix3Xd& lab, int steps, const Nearest& nearest,
                 TemplateFit& fit, double bound = std::numeric_limits<double>::infinity()) {
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
      if (step + 1 == steps && cost >= bound) {
        fit.cost = cost;
        return;
      }
      if (hit.squared_distance < kTemplateCap * kTemplateCap)
        shift += lab.col(i) - (placed.col(hit.index) + fit.translation), ++inliers;
    }
    fit.cost = cost;
    if (step + 1 < steps && inliers > 0) fit.translation += shift / inliers;
  }
}

/// The cost of `fit` (its height, heading, joints) with the translation refined by `steps`
/// nearest-point matching steps from fit.translation, each marker compared with every template
/// point; sets cost, translation, nearest, residual_mm (partial where the cost reaches `bound`:
/// match_steps).
inline void match_template(const body::BodyModel& base, const std::vector<TemplatePoint>& candidates,
                           const Eigen::Matrix3Xd& lab, int up, int steps, TemplateFit& fit,
                           double bound = std::numeric_limits<double>::infinity()) {
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
  match_steps(placed, lab, steps, scan, fit, bound);
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
          match_template(base, candidates, lab, up, 2, trial, fit.cost);
          if (trial.cost < fit.cost) fit = std::move(trial), improved = true;
        }
    }
  }
}

/// Fits the model, scaled to 1300-2100 mm and turned about the vertical `up` in 10 deg steps, at
/// its zero pose with the arms turned out 0-90 deg, to the marker positions `lab` by nearest
/// points, the translation refined by four matching steps (heights 100 mm apart first, then each
/// direction's two best placements 50 mm taller and shorter); where the best of these leaves an RMS
/// residual above `refine_above_rms_mm`, lets the pose vary (refine_pose) for the best direction
/// and its best rivals; compares the best direction with the best more than 60 deg away. Where the
/// near-zero pose fits, it is kept: refining it only trades a marker at a joint between the two
/// segments that meet there.
inline TemplateFit fit_template(const body::BodyModel& base, const std::vector<TemplatePoint>& candidates,
                                const Eigen::Matrix3Xd& lab, int up, double refine_above_rms_mm) {
  constexpr int kHeadings = 36;
  constexpr double kLowest = 1300, kTallest = 2100, kCoarseStep = 100;
  const std::vector<double> abductions{0.0, 0.4, 0.8, 1.2, 1.57};
  std::vector<TemplateFit> best_by_heading(kHeadings);
  std::vector<Eigen::Vector3d> start_by_heading(kHeadings, Eigen::Vector3d::Zero());
  const Eigen::VectorXd weights = centroid_weights(candidates);
  // A trial placement turns and scales a pose's points; the nearest point to a marker is found by
  // taking the marker back into the model's frame instead, in a tree built once per pose.
  std::vector<Eigen::VectorXd> poses;
  std::vector<Eigen::Matrix3Xd> model_points;
  std::vector<geometry::NearestPointTree> trees;
  for (const double abduction : abductions) {
    poses.push_back(arms_out(base, abduction));
    model_points.push_back(template_in_pose(base, candidates, poses.back()));
    trees.emplace_back(model_points.back());
  }
  // The cost of one placement, the best of each direction kept. A placement that can matter
  // neither as the direction's best nor below `wanted` stops early (match_steps): its cost is then
  // at least both.
  const auto place = [&](std::size_t pose, double height, int h, double wanted) {
    const auto hh = static_cast<std::size_t>(h);
    TemplateFit fit;
    fit.height = height, fit.heading = 2 * kPi * h / kHeadings;
    const Eigen::Matrix3d rotation = lab_from_model(up, fit.heading);
    const Eigen::Matrix3Xd placed = rotation * model_points[pose] * (height / 1000.0);
    // Start at the markers' centroid, feet on the lowest marker; the matching steps shift it.
    fit.translation = lab.rowwise().mean() - placed * weights;
    fit.translation(up) = lab.row(up).minCoeff() - placed.row(up).minCoeff();
    const Eigen::Vector3d start = fit.translation;
    const double scale = height / 1000.0, cap_in_model = kTemplateCap / scale;
    const auto search = [&](const Eigen::Vector3d& marker) {
      geometry::NearestPointTree::Hit hit =
          trees[pose].nearest(rotation.transpose() * marker / scale, cap_in_model * cap_in_model);
      if (hit.index >= 0) hit.squared_distance = (placed.col(hit.index) - marker).squaredNorm();
      return hit;
    };
    match_steps(placed, lab, 4, search, fit, std::max(wanted, best_by_heading[hh].cost));
    const double cost = fit.cost;
    if (cost < best_by_heading[hh].cost) {
      fit.joints = poses[pose];
      best_by_heading[hh] = std::move(fit);
      start_by_heading[hh] = start;
    }
    return cost;
  };
  // Coarse: each direction's two best (pose, height) placements, the second's cost the bound.
  struct Coarse {
    double cost = std::numeric_limits<double>::infinity();
    std::size_t pose = 0;
    double height = 0;
  };
  std::vector<std::array<Coarse, 2>> coarse(kHeadings);
  for (std::size_t pose = 0; pose < poses.size(); ++pose)
    for (double height = kLowest; height <= kTallest; height += kCoarseStep)
      for (int h = 0; h < kHeadings; ++h) {
        std::array<Coarse, 2>& two = coarse[static_cast<std::size_t>(h)];
        const double cost = place(pose, height, h, two[1].cost);
        if (cost < two[1].cost) two[1] = {cost, pose, height};
        if (two[1].cost < two[0].cost) std::swap(two[0], two[1]);
      }
  // Fine: halfway to the next coarse heights around each.
  for (int h = 0; h < kHeadings; ++h)
    for (const Coarse& around : coarse[static_cast<std::size_t>(h)])
      for (const double height : {around.height - kCoarseStep / 2, around.height + kCoarseStep / 2})
        if (std::isfinite(around.cost) && height >= kLowest && height <= kTallest)
          place(around.pose, height, h, 0.0);  // only the direction's best matters now
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

/// What every step reads: the recording, the points being placed, the template and the vertical.
struct InferenceContext {
  InferenceContext(const MarkerSequence& r, const SampleSet& s, const MarkerSetInferenceOptions& o)
      : recording(r), samples(s), options(o) {}
  const MarkerSequence& recording;
  const SampleSet& samples;
  const MarkerSetInferenceOptions& options;
  body::BodyModel base = body::mmm_body_model(1000);
  std::vector<int> points;  ///< the recording's points being placed (labelled, ever seen)
  std::vector<TemplatePoint> candidates;
  std::vector<long> template_frames;  ///< candidate frames for the template fit
  int up = 2;
  RigidClusters clusters;

  std::vector<int> shown_in(long f) const {
    std::vector<int> shown;
    for (int p : points)
      if (recording.visible(p, f)) shown.push_back(p);
    return shown;
  }
  Eigen::Matrix3Xd positions(long f, const std::vector<int>& shown) const {
    Eigen::Matrix3Xd lab(3, static_cast<Eigen::Index>(shown.size()));
    for (std::size_t i = 0; i < shown.size(); ++i)
      lab.col(static_cast<Eigen::Index>(i)) = recording.frame(f).col(shown[i]);
    return lab;
  }
  const std::string& label(int point) const { return recording.labels[static_cast<std::size_t>(point)]; }
};

/// The labelled points ever seen, `only` where given (else all); refuses a label used twice and
/// too few points or frames.
inline std::vector<int> inference_points(const MarkerSequence& recording,
                                         const MarkerSetInferenceOptions& options,
                                         const std::vector<int>* only = nullptr) {
  std::vector<int> points;
  std::map<std::string, int> seen;
  for (std::size_t p = 0; p < recording.labels.size(); ++p) {
    const std::string& label = recording.labels[p];
    if (label.empty() || !recording.visible.row(static_cast<Eigen::Index>(p)).any()) continue;
    if (only && std::find(only->begin(), only->end(), static_cast<int>(p)) == only->end()) continue;
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
  return points;
}

/// Step 1: the rigid clusters; a recording that is one rigid cluster is refused.
inline void find_clusters(InferenceContext& c) {
  c.clusters = find_rigid_clusters(c.recording, c.points, c.options.clusters);
  if (c.clusters.clusters.size() < 2)
    throw std::invalid_argument("all " + std::to_string(c.points.size()) +
                                " markers keep their mutual distances (one rigid cluster): nothing moves "
                                "against anything else, so no segment can be told from another");
}

/// Candidate template frames: up to options.template_frames, spread evenly over the frames that
/// show the most markers (a marker the template frame does not show is placed from the motion
/// alone, less surely); then the vertical: the axis along which their markers spread furthest (a
/// subject is taller than wide in most frames, whatever it does in a few).
inline void choose_template_frames(InferenceContext& c) {
  std::vector<long> visible_count(static_cast<std::size_t>(c.recording.frame_count()), 0);
  long most = 0;
  for (Eigen::Index f = 0; f < c.recording.frame_count(); ++f) {
    for (int p : c.points) visible_count[static_cast<std::size_t>(f)] += c.recording.visible(p, f) ? 1 : 0;
    most = std::max(most, visible_count[static_cast<std::size_t>(f)]);
  }
  std::vector<long> well_seen;
  for (std::size_t f = 0; f < visible_count.size(); ++f)
    if (visible_count[f] == most) well_seen.push_back(static_cast<long>(f));
  const long wanted = std::max(1, c.options.template_frames);
  c.template_frames.clear();
  for (long k = 0; k < std::min<long>(wanted, static_cast<long>(well_seen.size())); ++k)
    c.template_frames.push_back(
        well_seen[static_cast<std::size_t>(k * static_cast<long>(well_seen.size()) / wanted)]);
  c.up = c.options.up_axis;
  if (c.up < 0) {
    Eigen::Vector3d extent = Eigen::Vector3d::Zero();
    for (long f : c.template_frames) {
      const Eigen::Matrix3Xd lab = c.positions(f, c.shown_in(f));
      extent += lab.rowwise().maxCoeff() - lab.rowwise().minCoeff();
    }
    extent.maxCoeff(&c.up);
  }
  if (c.up > 2) throw std::invalid_argument("the vertical axis must be 0 (x), 1 (y) or 2 (z)");
}

/// One candidate frame's template fit.
struct FramedFit {
  long frame = 0;
  TemplateFit fit;
};

/// Step 2: the template fit in every candidate frame. Shortlisted: the frames whose facing
/// direction wins clearly (beyond options.heading_margin), those where the zero pose fitted first
/// (the subject stands there, and the standing subject defines the zero of the joint angles, as the
/// model's zero pose does), then the clearest, at most options.template_attempts.
inline std::vector<FramedFit> shortlist_template_fits(const InferenceContext& c, bool by_residual = false) {
  std::vector<TemplateFit> trials(c.template_frames.size());
  parallel_for(static_cast<int>(trials.size()), c.options.threads, [&](int k) {
    const long f = c.template_frames[static_cast<std::size_t>(k)];
    trials[static_cast<std::size_t>(k)] = fit_template(c.base, c.candidates, c.positions(f, c.shown_in(f)),
                                                       c.up, c.options.refine_pose_above_rms_mm);
  });
  std::vector<FramedFit> clear;
  double best_margin = 0;
  long best_margin_frame = c.template_frames.front();
  for (std::size_t k = 0; k < trials.size(); ++k) {
    const long f = c.template_frames[k];
    TemplateFit& trial = trials[k];
    if (trial.margin > best_margin) best_margin = trial.margin, best_margin_frame = f;
    if (trial.margin > c.options.heading_margin) clear.push_back({f, std::move(trial)});
  }
  if (clear.empty()) {
    std::ostringstream s;
    s << "the subject's facing direction is ambiguous in all " << c.template_frames.size()
      << " well-seen frames tried (the best fit of the body model, in frame " << best_margin_frame
      << ", is only " << std::lround(100 * (best_margin - 1))
      << " % better than one facing more than 60 degrees away); give a marker set (--markerset)";
    throw std::invalid_argument(s.str());
  }
  std::stable_sort(clear.begin(), clear.end(), [by_residual](const FramedFit& a, const FramedFit& b) {
    if (a.fit.pose_refined != b.fit.pose_refined) return b.fit.pose_refined;
    if (by_residual && a.fit.pose_refined) return a.fit.cost < b.fit.cost;
    return a.fit.margin > b.fit.margin;
  });
  if (!clear.front().fit.pose_refined)
    clear.erase(
        std::remove_if(clear.begin(), clear.end(), [](const FramedFit& f) { return f.fit.pose_refined; }),
        clear.end());
  clear.resize(std::min<std::size_t>(clear.size(),
                                     static_cast<std::size_t>(std::max(1, c.options.template_attempts))));
  return clear;
}

/// Points far from every template point (beyond the cost's cap) in most of the shortlisted fits
/// are no markers on the skin: a lab's virtual points (segment origins and axes written as
/// points), a stray. They leave c.points (but for `keep`), the fits are matched again, and the
/// note says which; `left_out` receives them.
inline std::string leave_out_far_points(InferenceContext& c, std::vector<FramedFit>& shortlist,
                                        const std::vector<int>& keep,
                                        std::vector<int>* left_out_points = nullptr) {
  std::map<int, int> far, shown_count;
  for (const FramedFit& framed : shortlist) {
    const std::vector<int> shown = c.shown_in(framed.frame);
    for (std::size_t k = 0; k < shown.size(); ++k) {
      ++shown_count[shown[k]];
      if (framed.fit.residual_mm[k] > kTemplateCap) ++far[shown[k]];
    }
  }
  std::vector<int> kept_points;
  std::vector<std::string> left_out;
  for (int p : c.points)
    if (2 * far[p] > shown_count[p] && std::find(keep.begin(), keep.end(), p) == keep.end()) {
      left_out.push_back(c.label(p));
      if (left_out_points) left_out_points->push_back(p);
    } else {
      kept_points.push_back(p);
    }
  if (left_out.empty()) return {};
  if (kept_points.size() < 8)
    throw std::invalid_argument("only " + std::to_string(kept_points.size()) +
                                " points lie near the body model's surface in the template fit; at least 8 "
                                "are needed to infer a marker set");
  std::ostringstream s;
  s << "left out " << left_out.size() << " points far (over " << std::lround(kTemplateCap)
    << " mm) from the body's surface in the template fit, no markers on the skin:";
  for (std::size_t k = 0; k < left_out.size(); ++k) s << (k < 12 ? " " + left_out[k] : k == 12 ? " ..." : "");
  c.points = kept_points;
  for (FramedFit& framed : shortlist)
    match_template(c.base, c.candidates, c.positions(framed.frame, c.shown_in(framed.frame)), c.up, 1,
                   framed.fit);
  return s.str();
}

/// A set grown from one template fit: its frames, the rounds' last spreads, and what was done.
struct Attempt {
  long template_frame = 0;
  std::vector<int> frame_of;  ///< per point of the context, its model frame
  body::MarkerSet set;        ///< per point of the context, its entry
  /// Per point, where the template fit puts it (model coordinates, 1000 mm); none where the
  /// template frame does not show it.
  std::vector<std::optional<Eigen::Vector3d>> standing;
  body::FrameTransforms template_pose;  ///< the model's frames at the fitted pose, 1000 mm
  FrameSpread spread;
  double height = 0;
  int rounds = 0;
  double spread_rms_mm = std::numeric_limits<double>::infinity();  ///< over markers on their frames
  std::vector<std::string> notes;
  std::vector<std::string> cluster_notes;  ///< clusters placed by their name, or narrowly by their motion
};

/// Puts point i of the attempt on its frame: where the template fit puts it, else at `fallback`
/// (1000 mm, in the frame).
inline void place_point(const InferenceContext& c, Attempt& a, std::size_t i,
                        const Eigen::Vector3d& fallback) {
  const auto k = static_cast<std::size_t>(a.frame_of[i]);
  a.set.entries[i].frame = body::marker_set_frame_name(c.base, a.frame_of[i]);
  a.set.entries[i].offset = a.standing[i] ? Eigen::Vector3d(a.template_pose.rotations[k].transpose() *
                                                            (*a.standing[i] - a.template_pose.origins[k]))
                                          : fallback;
}

/// Step 2 (end) and 3: the initial set from one template fit, every marker on the frame of its
/// nearest template point, its offset where the fitted pose puts it (the standing subject defines
/// the zero of the joint angles, as the model's zero pose does; offsets measured from tracked
/// frames would carry the first rounds' errors into the set); then the topology check.
inline Attempt initial_assignment(const InferenceContext& c, const FramedFit& framed, std::size_t tried,
                                  const std::string& excluded_note) {
  const TemplateFit& fit = framed.fit;
  Attempt a;
  a.template_frame = framed.frame;
  const std::vector<int> shown = c.shown_in(framed.frame);
  const Eigen::Matrix3Xd lab = c.positions(framed.frame, shown);
  a.template_pose =
      body::joint_frames(c.base, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), fit.joints);
  const Eigen::Matrix3d rotation = lab_from_model(c.up, fit.heading);
  a.standing.assign(c.points.size(), std::nullopt);
  a.frame_of.assign(c.points.size(), 0);
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    const auto at = std::find(shown.begin(), shown.end(), c.points[i]);
    if (at == shown.end()) continue;
    const auto column = at - shown.begin();
    a.frame_of[i] =
        c.candidates[static_cast<std::size_t>(fit.nearest[static_cast<std::size_t>(column)])].frame;
    a.standing[i] =
        Eigen::Vector3d(rotation.transpose() * (lab.col(column) - fit.translation) * (1000.0 / fit.height));
  }
  Eigen::Index largest = 0;
  std::ostringstream fitted;
  fitted << "template fit in frame " << framed.frame << " (" << c.template_frames.size()
         << " well-seen frames fitted, " << tried << " tried): "
         << "xyz"[c.up] << " up, height " << std::lround(fit.height) << " mm, largest joint angle "
         << std::lround(fit.joints.cwiseAbs().maxCoeff(&largest) * 180 / kPi) << " deg ("
         << c.base.joints[static_cast<std::size_t>(largest)].name << "), facing "
         << std::lround(fit.heading * 180 / kPi) << " deg (the next direction more than 60 deg away costs "
         << std::lround(100 * (fit.margin - 1)) << " % more), RMS residual " << std::lround(fit.rms_mm())
         << " mm";
  a.notes.push_back(fitted.str());
  if (!excluded_note.empty()) a.notes.push_back(excluded_note);

  // The topology check (segment_rigidity.hpp): a marker whose distances to its segment's markers
  // vary by centimetres but stay constant to another segment's moves there (the template put a
  // thigh marker on the hand hanging beside it). Markers the template frame does not show go to
  // the segment whose markers keep the steadiest distances to them.
  std::vector<int> placed_points, placed_frames;
  std::vector<std::size_t> placed_index;
  for (std::size_t i = 0; i < c.points.size(); ++i)
    if (a.standing[i])
      placed_points.push_back(c.points[i]), placed_frames.push_back(a.frame_of[i]), placed_index.push_back(i);
  for (const SegmentMove& move :
       repair_segment_assignment(c.clusters, c.base, placed_points, placed_frames, c.options.rigidity)) {
    std::ostringstream s;
    s << "moved " << c.label(placed_points[move.marker]) << " from " << move.from << " to " << move.to
      << ": its distances to the markers of " << move.from << " vary by " << std::lround(move.from_sd_mm)
      << " mm (median SD), to those of " << move.to << " by " << std::lround(move.to_sd_mm) << " mm";
    a.notes.push_back(s.str());
  }
  for (std::size_t j = 0; j < placed_index.size(); ++j) a.frame_of[placed_index[j]] = placed_frames[j];
  const auto placed_by_segment = points_by_segment(c.base, placed_points, placed_frames);
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    if (a.standing[i]) continue;
    double steadiest = std::numeric_limits<double>::infinity();
    for (const auto& [segment, members] : placed_by_segment) {
      const double sd = median_distance_sd(c.clusters, c.points[i], members);
      if (!(sd < steadiest)) continue;
      steadiest = sd;
      for (std::size_t j = 0; j < placed_points.size(); ++j)
        if (body::segment_of_frame(c.base, placed_frames[j]) == segment) a.frame_of[i] = placed_frames[j];
    }
  }

  a.set.name = "inferred";
  a.set.reference_height_mm = 1000.0;
  a.set.entries.resize(c.points.size());
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    a.set.entries[i].label = c.label(c.points[i]);
    place_point(c, a, i, Eigen::Vector3d::Zero());
  }
  a.height = fit.height;
  return a;
}

/// Markers a lab mounts together on one rigid plate (a cluster): labels that differ in their last
/// character only (LTBA-LTBD), three or more, whose mutual distances stay steady in the recording.
/// They are placed as a unit, on the segment whose motion explains all of them best.
struct MarkerCluster {
  std::string stem;                  ///< the shared label without its last character, upper case
  std::vector<std::size_t> members;  ///< indices into the context's points
  std::string named_segment;         ///< the segment its name says by the convention below, or ""
};

/// The segment a cluster's name says by the Vicon convention for cluster models (PELA-PELD on the
/// pelvis; side L or R, then FM femur, TB tibia, FT foot; TH thigh, SH or SK shank as other labs
/// write them), or "" where the name says nothing.
inline std::string named_cluster_segment(const std::string& stem) {
  if (stem == "PEL") return "root";
  if (stem.size() != 3 || (stem[0] != 'L' && stem[0] != 'R')) return {};
  const std::string kind = stem.substr(1), side(1, stem[0]);
  if (kind == "FM" || kind == "TH") return side + "H";
  if (kind == "TB" || kind == "SH" || kind == "SK") return side + "K";
  if (kind == "FT") return side + "A";
  return {};
}

/// The segment a single marker's name says where its motion hardly can: a greater trochanter
/// (side L or R, then GT, GTR or TROC: LGT, RGTR) rides on the thigh, though it sits at the hip
/// joint, where the pelvis carries it nearly as steadily. "" where the name says nothing.
inline std::string named_marker_segment(const std::string& label) {
  const std::string name = upper_case(label);
  if (name.size() < 3 || (name[0] != 'L' && name[0] != 'R')) return {};
  const std::string kind = name.substr(1);
  if (kind == "GT" || kind == "GTR" || kind == "TROC") return std::string(1, name[0]) + "H";
  return {};
}

/// A cluster's markers keep their mutual distances within this (median SD, mm): soft tissue moves
/// the simulated subjects' markers by 8 mm each, a joint between two of them by centimetres.
inline constexpr double kClusterSteadySdMm = 20.0;

/// Whether a cluster's stem names something: it holds a letter. Capture software numbers the
/// trajectories it could not label (Vicon's *115, *116, ...): a shared count is no shared plate.
inline bool stem_is_a_name(const std::string& stem) {
  return std::any_of(stem.begin(), stem.end(),
                     [](char ch) { return std::isalpha(static_cast<unsigned char>(ch)); });
}

/// The clusters among the points not `fixed`, by their labels; steady ones only.
inline std::vector<MarkerCluster> label_clusters(const InferenceContext& c, const std::vector<bool>& fixed) {
  std::map<std::string, std::vector<std::size_t>> by_stem;
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    if (!fixed.empty() && fixed[i]) continue;
    const std::string label = upper_case(c.label(c.points[i]));
    const char last = label.empty() ? ' ' : label.back();
    if (label.size() < 3 || !((last >= 'A' && last <= 'H') || (last >= '1' && last <= '9'))) continue;
    if (!stem_is_a_name(label.substr(0, label.size() - 1))) continue;
    by_stem[label.substr(0, label.size() - 1)].push_back(i);
  }
  std::vector<MarkerCluster> clusters;
  for (const auto& [stem, members] : by_stem) {
    if (members.size() < 3 || members.size() > 6) continue;
    std::vector<double> sd;
    for (std::size_t a = 0; a < members.size(); ++a)
      for (std::size_t b = a + 1; b < members.size(); ++b) {
        const double d = c.clusters.distance_sd(c.points[members[a]], c.points[members[b]]);
        if (std::isfinite(d)) sd.push_back(d);
      }
    if (sd.empty()) continue;
    std::nth_element(sd.begin(), sd.begin() + static_cast<std::ptrdiff_t>(sd.size() / 2), sd.end());
    if (!(sd[sd.size() / 2] < kClusterSteadySdMm)) continue;
    clusters.push_back({stem, members, named_cluster_segment(stem)});
  }
  return clusters;
}

/// Whether any point of the attempt rides on `segment`.
inline bool segment_carries_markers(const InferenceContext& c, const Attempt& a, const std::string& segment) {
  for (std::size_t i = 0; i < c.points.size(); ++i)
    if (body::segment_of_frame(c.base, a.frame_of[i]) == segment) return true;
  return false;
}

/// The frame of `segment` that carries point i steadiest (the segment's own frame where none was
/// measured).
inline int steadiest_frame_on(const InferenceContext& c, const Attempt& a, std::size_t i,
                              const std::string& segment) {
  int frame = c.base.frame_index(segment);
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < c.base.frame_count(); ++k)
    if (body::segment_of_frame(c.base, k) == segment &&
        a.spread.spread(static_cast<Eigen::Index>(i), k) < best)
      frame = k, best = a.spread.spread(static_cast<Eigen::Index>(i), k);
  return frame;
}

/// One cluster's candidate segments (those its markers are on, the ones next to them, the one its
/// name says) and how steadily each carries it in the last round of tracking.
struct ClusterCandidates {
  const InferenceContext& c;
  const Attempt& a;
  const MarkerCluster& cluster;
  std::vector<std::string> segments;

  ClusterCandidates(const InferenceContext& context, const Attempt& attempt, const MarkerCluster& unit)
      : c(context), a(attempt), cluster(unit) {
    for (std::size_t i : cluster.members) {
      const std::string segment = body::segment_of_frame(c.base, a.frame_of[i]);
      add(segment);
      for (const std::string& next : adjacent_segments(c.base, segment)) add(next);
    }
    add(cluster.named_segment);
  }
  void add(const std::string& segment) {
    if (!segment.empty() && std::find(segments.begin(), segments.end(), segment) == segments.end())
      segments.push_back(segment);
  }
  /// Whether any point rides on `segment` now: else its tracked motion is the prior's, no evidence.
  bool carries_markers(const std::string& segment) const { return segment_carries_markers(c, a, segment); }
  /// The RMS over the members of their spread on the segment's steadiest frame for each.
  double cost_on(const std::string& segment) const {
    double sum2 = 0;
    for (std::size_t i : cluster.members) {
      double best = std::numeric_limits<double>::infinity();
      for (int k = 0; k < c.base.frame_count(); ++k)
        if (body::segment_of_frame(c.base, k) == segment)
          best = std::min(best, a.spread.spread(static_cast<Eigen::Index>(i), k));
      sum2 += best * best;
    }
    return std::sqrt(sum2 / static_cast<double>(cluster.members.size()));
  }
  /// The steadiest segment that carries markers, other than `except`; "" where none.
  std::string steadiest(const std::string& except = {}) const {
    std::string best;
    for (const std::string& segment : segments)
      if (segment != except && carries_markers(segment) && std::isfinite(cost_on(segment)) &&
          (best.empty() || cost_on(segment) < cost_on(best)))
        best = segment;
    return best;
  }
};

inline const char* segment_kind(const std::string& segment) {
  if (segment.size() < 2) return "";
  return segment[1] == 'H' ? "thigh" : segment[1] == 'K' ? "shank" : segment[1] == 'A' ? "foot" : "pelvis";
}

/// The segment a cluster goes to: the motion's choice, or its name's where the motion does not
/// separate the two (spreads within 1 / move_ratio) or the named segment carries no marker. `note`
/// says so, or where the motion's choice is narrow or beside a segment that carries no marker and
/// no name confirms it.
inline std::string choose_cluster_segment(const ClusterCandidates& candidates, double move_ratio,
                                          std::ostringstream& note) {
  const std::string& stem = candidates.cluster.stem;
  const std::string& named = candidates.cluster.named_segment;
  const std::string by_motion = candidates.steadiest();
  const double best_cost =
      by_motion.empty() ? std::numeric_limits<double>::infinity() : candidates.cost_on(by_motion);
  if (!named.empty() && named != by_motion) {
    const bool named_empty = !candidates.carries_markers(named);
    const double named_cost = candidates.cost_on(named);
    if (named_empty || by_motion.empty() || named_cost * move_ratio < best_cost) {
      note << stem << "* on " << named << " by its name (" << segment_kind(named)
           << " by the cluster-model convention): ";
      if (named_empty)
        note << named << " carried no marker, so its motion could not be compared with " << by_motion << "'s";
      else
        note << "the motion does not separate " << named << " from " << by_motion << " (spread "
             << std::lround(named_cost) << " against " << std::lround(best_cost) << " mm)";
      return named;
    }
  }
  if (by_motion.empty()) return by_motion;
  const std::string runner_up = candidates.steadiest(by_motion);
  const double runner_cost =
      runner_up.empty() ? std::numeric_limits<double>::infinity() : candidates.cost_on(runner_up);
  if (!runner_up.empty() && runner_cost * move_ratio < best_cost) {
    note << stem << "* on " << by_motion << ": the motion hardly separates " << by_motion << " from "
         << runner_up << " (spread " << std::lround(best_cost) << " against " << std::lround(runner_cost)
         << " mm)";
    if (named == by_motion)
      note << ", and its name says " << segment_kind(named);
    else
      note << "; no name says which: check it";
  } else if (named != by_motion) {
    // A neighbour that carries no marker has no tracked motion to compare with.
    for (const std::string& segment : adjacent_segments(candidates.c.base, by_motion))
      if (!candidates.carries_markers(segment)) {
        note << stem << "* on " << by_motion << ": " << segment
             << " next to it carries no marker, so the motion cannot tell whether " << stem
             << "* rides there instead, and no name says which: check it";
        break;
      }
  }
  return by_motion;
}

/// Places each cluster as a unit (clusters: label_clusters) on the segment choose_cluster_segment
/// gives, all its markers on that segment's own frame (after every DoF of its joint): a rigid plate
/// rides on one bone, and members left on the joint's intermediate frames would not see the angles
/// after them (a foot plate's markers on LAx do not see the inversion). `place(i, frame)` sets its
/// offset. Returns the markers moved; `notes` (by stem) holds each cluster's note, if any.
template <class Place>
int place_clusters_as_units(const InferenceContext& c, Attempt& a, const std::vector<MarkerCluster>& clusters,
                            const Place& place, std::map<std::string, std::string>& notes) {
  int moved = 0;
  for (const MarkerCluster& cluster : clusters) {
    std::ostringstream note;
    const std::string chosen =
        choose_cluster_segment(ClusterCandidates(c, a, cluster), c.options.move_ratio, note);
    if (note.str().empty())
      notes.erase(cluster.stem);
    else
      notes[cluster.stem] = note.str();
    if (chosen.empty()) continue;
    const int frame = c.base.frame_index(chosen);
    for (std::size_t i : cluster.members) {
      if (a.frame_of[i] == frame) continue;
      a.frame_of[i] = frame;
      place(i, frame);
      ++moved;
    }
  }
  return moved;
}

/// Two clusters on one segment whose mutual distances vary clearly more than each one's own
/// (median SD over this multiple of the mean of theirs) ride on two segments with a joint between.
inline constexpr double kSplitClusterRatio = 1.5;

/// The median distance SD (mm) between the markers of `x` and `y`, or within `x` where they are
/// the same cluster; NaN where no pair was seen together often enough.
inline double cluster_distance_sd(const InferenceContext& c, const MarkerCluster& x, const MarkerCluster& y) {
  std::vector<double> sd;
  for (std::size_t i : x.members)
    for (std::size_t j : y.members) {
      if (&x == &y && j <= i) continue;
      const double d = c.clusters.distance_sd(c.points[i], c.points[j]);
      if (std::isfinite(d)) sd.push_back(d);
    }
  if (sd.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(sd.begin(), sd.begin() + static_cast<std::ptrdiff_t>(sd.size() / 2), sd.end());
  return sd[sd.size() / 2];
}

/// After the clusters are placed: two clusters that share a segment but not its rigidity
/// (kSplitClusterRatio) are on two segments. Where a segment next to theirs carries no marker,
/// the motion could not place either there (an empty segment's tracked motion is the prior's), so
/// the cluster nearer the joint to it goes there (a foot cluster below the shank's, renamed
/// beyond what the cluster-model names say). Returns the markers moved; `notes` as
/// place_clusters_as_units.
template <class Place>
int split_clusters_sharing_a_segment(const InferenceContext& c, Attempt& a,
                                     const std::vector<MarkerCluster>& clusters, const Place& place,
                                     std::map<std::string, std::string>& notes) {
  const auto segment_of = [&](std::size_t i) { return body::segment_of_frame(c.base, a.frame_of[i]); };
  const auto on_one_segment = [&](const MarkerCluster& k) {
    for (std::size_t i : k.members)
      if (segment_of(i) != segment_of(k.members.front())) return false;
    return true;
  };
  // Mean distance (tracked mm) of a cluster's markers from the origin of `frame`.
  const auto distance_from = [&](const MarkerCluster& k, int frame) {
    double sum = 0;
    int count = 0;
    for (std::size_t i : k.members)
      if (std::isfinite(a.spread.spread(static_cast<Eigen::Index>(i), frame)))
        sum += a.spread.mean[i][static_cast<std::size_t>(frame)].norm(), ++count;
    return count ? sum / count : std::numeric_limits<double>::infinity();
  };
  int moved = 0;
  for (std::size_t x = 0; x < clusters.size(); ++x)
    for (std::size_t y = x + 1; y < clusters.size(); ++y) {
      const MarkerCluster &cx = clusters[x], &cy = clusters[y];
      const std::string shared = segment_of(cx.members.front());
      if (!on_one_segment(cx) || !on_one_segment(cy) || segment_of(cy.members.front()) != shared) continue;
      const double across = cluster_distance_sd(c, cx, cy);
      const double own = 0.5 * (cluster_distance_sd(c, cx, cx) + cluster_distance_sd(c, cy, cy));
      if (!(across > kSplitClusterRatio * own)) continue;
      const MarkerCluster* nearer = nullptr;
      std::string target;
      double nearest = std::numeric_limits<double>::infinity();
      for (const std::string& empty : adjacent_segments(c.base, shared)) {
        if (segment_carries_markers(c, a, empty)) continue;
        // The joint between them is the child's origin.
        bool child = false;
        for (const body::Joint& joint : c.base.joints)
          if (joint.group == empty && body::segment_of_frame(c.base, joint.parent_frame) == shared)
            child = true;
        const int joint_frame = c.base.frame_index(child ? empty : shared);
        for (const MarkerCluster* k : {&cx, &cy})
          if (const double d = distance_from(*k, joint_frame); d < nearest)
            nearest = d, nearer = k, target = empty;
      }
      if (!nearer) continue;
      const int frame = c.base.frame_index(target);  // the segment's own, as place_clusters_as_units
      for (std::size_t i : nearer->members) {
        a.frame_of[i] = frame;
        place(i, frame);
        ++moved;
      }
      const MarkerCluster& other = nearer == &cx ? cy : cx;
      std::ostringstream note;
      note << nearer->stem << "* on " << target << ", not " << shared << " with " << other.stem
           << "*: their mutual distances vary by " << std::lround(across) << " mm (median SD) against "
           << std::lround(own) << " mm within each, so a joint lies between them, " << target << " next to "
           << shared << " carried no marker, and " << nearer->stem
           << "* is the nearer to that joint; no name says which: check it";
      notes[nearer->stem] = note.str();
    }
  return moved;
}

/// Step 4: rounds of tracking and reassignment. A marker moves only to a neighbouring segment
/// (its parent or a child): the template fit and the topology check placed it near its segment,
/// and a distant segment can look rigid with it only where the tracking of both failed. A marker
/// the template frame does not show takes its mean position on its frame over the tracked frames.
/// Points marked `fixed` (a known set's) are tracked with and measured but never moved; another
/// point on a segment that carries a fixed one takes its mean tracked position there, not the
/// template's: the fixed markers define that segment's pose. Elsewhere (a segment only clusters
/// ride on) the template's fitted pose stays the only reference for the zero of its joint angles.
inline void reassignment_rounds(const InferenceContext& c, Attempt& a, const std::vector<bool>& fixed = {},
                                const std::vector<MarkerCluster>& clusters = {}) {
  std::vector<bool> in_cluster(c.points.size(), false);
  for (const MarkerCluster& cluster : clusters)
    for (std::size_t i : cluster.members) in_cluster[i] = true;
  std::map<std::string, std::string> cluster_notes;
  std::map<std::string, std::string> parent_segment;
  for (const body::Joint& joint : c.base.joints)
    parent_segment.emplace(joint.group, body::segment_of_frame(c.base, joint.parent_frame));
  const auto neighbours = [&](int x, int y) {
    const std::string sx = body::segment_of_frame(c.base, x), sy = body::segment_of_frame(c.base, y);
    return sx == sy || parent_segment[sx] == sy || parent_segment[sy] == sx;
  };
  const MarkerSetInferenceOptions& options = c.options;
  std::vector<std::string> anchored;  // segments that carry a fixed point
  for (std::size_t i = 0; i < fixed.size(); ++i)
    if (fixed[i]) anchored.push_back(body::segment_of_frame(c.base, a.frame_of[i]));
  const auto from_motion = [&](int frame) {
    return std::find(anchored.begin(), anchored.end(), body::segment_of_frame(c.base, frame)) !=
           anchored.end();
  };
  const std::vector<int> template_frame_of = a.frame_of;  // after the topology check
  for (int round = 0; round < options.max_rounds; ++round) {
    double estimated = a.height;
    a.spread = track_and_measure(c.recording, c.points, a.set, round == 0 ? a.height : 0.0, c.samples,
                                 options, estimated);
    a.height = estimated;
    int moved = 0;
    for (std::size_t i = 0; i < c.points.size(); ++i) {
      if (!fixed.empty() && fixed[i]) continue;
      const auto row = static_cast<Eigen::Index>(i);
      if (in_cluster[i]) {  // placed with its cluster below; its offset as any marker's where it stays
        const double own = a.spread.spread(row, a.frame_of[i]);
        if ((from_motion(a.frame_of[i]) || !a.standing[i]) && std::isfinite(own)) {
          if (from_motion(a.frame_of[i])) a.standing[i].reset();
          place_point(c, a, i,
                      a.spread.mean[i][static_cast<std::size_t>(a.frame_of[i])] * (1000.0 / a.height));
        }
        continue;
      }
      int best_frame = a.frame_of[i];
      double best_spread = std::numeric_limits<double>::infinity();
      for (int k = 0; k < c.base.frame_count(); ++k)
        if (neighbours(a.frame_of[i], k) && a.spread.spread(row, k) < best_spread)
          best_frame = k, best_spread = a.spread.spread(row, k);
      if (!std::isfinite(best_spread)) continue;
      const double own = a.spread.spread(row, a.frame_of[i]);
      if (std::isfinite(own) && (own < options.rigid_spread_mm || !(best_spread < options.move_ratio * own)))
        best_frame = a.frame_of[i];
      // Off the template's frame, back to it where it now carries the marker rigidly and steadier: the
      // round that moved it had lost the segment's tracking (an arm for a round), not found its place.
      const int on_template = template_frame_of[i];
      const double template_spread = a.spread.spread(row, on_template);
      if (a.frame_of[i] != on_template && template_spread < options.rigid_spread_mm &&
          template_spread < std::min(own, a.spread.spread(row, best_frame)))
        best_frame = on_template;
      // Its name decides where the motion does not separate the named segment from the steadiest.
      const std::string named = named_marker_segment(c.label(c.points[i]));
      if (!named.empty() && body::segment_of_frame(c.base, best_frame) != named) {
        const int on_named = steadiest_frame_on(c, a, i, named);
        const double named_spread = a.spread.spread(row, on_named);
        if (neighbours(a.frame_of[i], on_named) && std::isfinite(named_spread) &&
            named_spread * options.move_ratio < std::min(best_spread, std::isfinite(own) ? own : best_spread))
          best_frame = on_named;
      }
      if (best_frame == a.frame_of[i]) {
        if ((from_motion(best_frame) || !a.standing[i]) && std::isfinite(own)) {
          if (from_motion(best_frame)) a.standing[i].reset();
          place_point(c, a, i, a.spread.mean[i][static_cast<std::size_t>(best_frame)] * (1000.0 / a.height));
        }
        continue;
      }
      ++moved;
      a.frame_of[i] = best_frame;
      if (from_motion(best_frame)) a.standing[i].reset();
      place_point(c, a, i, a.spread.mean[i][static_cast<std::size_t>(best_frame)] * (1000.0 / a.height));
    }
    // Puts point i on frame `frame` where the motion measured it there (else at the frame's origin).
    const auto move_point = [&](std::size_t i, int frame) {
      const bool measured = std::isfinite(a.spread.spread(static_cast<Eigen::Index>(i), frame));
      if (from_motion(frame) && measured) a.standing[i].reset();
      place_point(
          c, a, i,
          measured ? Eigen::Vector3d(a.spread.mean[i][static_cast<std::size_t>(frame)] * (1000.0 / a.height))
                   : Eigen::Vector3d::Zero());
    };
    moved += place_clusters_as_units(c, a, clusters, move_point, cluster_notes);
    moved += split_clusters_sharing_a_segment(c, a, clusters, move_point, cluster_notes);
    a.rounds = round + 1;
    if (moved == 0) break;
  }
  double total2 = 0;
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    const double own = a.spread.spread(static_cast<Eigen::Index>(i), a.frame_of[i]);
    const double o = std::isfinite(own) ? own : options.max_spread_mm * 10;
    total2 += o * o;
  }
  a.spread_rms_mm = std::sqrt(total2 / static_cast<double>(c.points.size()));
  for (const auto& [stem, note] : cluster_notes) a.cluster_notes.push_back(note);
}

/// A marker's confidence and spread on its segment.
struct PlacedMarker {
  double spread_mm = 0;  ///< on its segment; max_spread_mm * 10 where never measured
  double confidence = 0;
};

/// Step 5: the confidence of every marker: the motion's (1 - spread on its segment / spread on
/// the best other), lowered to the topology's where that is weaker (1 - median distance SD to its
/// segment's markers / that to the best other segment's), and halved for a marker alone on its
/// segment, which no other marker can check.
inline std::vector<PlacedMarker> marker_confidence(const InferenceContext& c, const Attempt& a) {
  const std::vector<MarkerRigidity> rigidity = marker_rigidity(c.clusters, c.base, c.points, a.frame_of);
  std::vector<PlacedMarker> placed(c.points.size());
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    const std::string segment = body::segment_of_frame(c.base, a.frame_of[i]);
    const double own = a.spread.spread(row, a.frame_of[i]);
    double other = std::numeric_limits<double>::infinity();
    for (int k = 0; k < c.base.frame_count(); ++k)
      if (body::segment_of_frame(c.base, k) != segment) other = std::min(other, a.spread.spread(row, k));
    double confidence = std::isfinite(other) && std::isfinite(own) ? std::max(0.0, 1.0 - own / other) : 0.0;
    const MarkerRigidity& r = rigidity[i];
    if (!std::isfinite(r.own_sd_mm))
      confidence *= 0.5;
    else if (std::isfinite(r.best_other_sd_mm))
      confidence = std::min(confidence, std::max(0.0, 1.0 - r.own_sd_mm / r.best_other_sd_mm));
    placed[i] = {std::isfinite(own) ? own : c.options.max_spread_mm * 10, confidence};
  }
  return placed;
}

}  // namespace detail

S2KF_INLINE InferredMarkerSet infer_marker_set(const MarkerSequence& recording, const SampleSet& samples,
                                               const MarkerSetInferenceOptions& options) {
  detail::InferenceContext c{recording, samples, options};
  c.points = detail::inference_points(recording, options);
  InferredMarkerSet result;
  detail::find_clusters(c);
  result.clusters = c.clusters;
  detail::choose_template_frames(c);
  result.up_axis = c.up;
  c.candidates = detail::template_points(c.base, options.known_sets);
  std::vector<detail::FramedFit> shortlist = detail::shortlist_template_fits(c);
  const std::string excluded_note = detail::leave_out_far_points(c, shortlist, {});

  // Each shortlisted fit is carried through the rounds; the one whose markers then ride most
  // rigidly on their segments is kept.
  std::vector<detail::Attempt> attempts(shortlist.size());
  parallel_for(static_cast<int>(shortlist.size()), options.threads, [&](int k) {
    detail::Attempt& a = attempts[static_cast<std::size_t>(k)];
    a = detail::initial_assignment(c, shortlist[static_cast<std::size_t>(k)], shortlist.size(),
                                   excluded_note);
    detail::reassignment_rounds(c, a);
  });
  detail::Attempt kept;
  for (detail::Attempt& a : attempts)
    if (a.spread_rms_mm < kept.spread_rms_mm) kept = std::move(a);
  result.template_frame = kept.template_frame;
  result.rounds = kept.rounds;
  result.height_mm = kept.height;
  result.notes = kept.notes;

  const std::vector<detail::PlacedMarker> placed = detail::marker_confidence(c, kept);
  std::map<std::string, InferredSegment> by_segment;
  double total2 = 0;
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    InferredSegment& s = by_segment[body::segment_of_frame(c.base, kept.frame_of[i])];
    s.segment = body::segment_of_frame(c.base, kept.frame_of[i]);
    ++s.markers;
    s.spread_mm += placed[i].spread_mm * placed[i].spread_mm;
    s.confidence += placed[i].confidence;
    total2 += placed[i].spread_mm * placed[i].spread_mm;
  }
  result.spread_mm = std::sqrt(total2 / static_cast<double>(c.points.size()));
  for (int k = 0; k < c.base.frame_count(); ++k) {
    const auto found = by_segment.find(body::segment_of_frame(c.base, k));
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

  body::MarkerSet& set = kept.set;
  std::ostringstream description;
  description << "Inferred by s2kf from the recording's motion (" << result.clusters.clusters.size()
              << " rigid clusters; " << kept.notes.front() << "; " << result.rounds
              << " round(s) of tracking and reassignment). Segment, markers, confidence:";
  for (const InferredSegment& s : result.segments)
    description << " " << s.segment << " " << s.markers << " " << std::lround(100 * s.confidence) << " %;";
  description << " check the frames and correct them by hand where the confidence is low.";
  set.description = description.str();
  result.set = set;
  return result;
}

}  // namespace s2kf::markerset
