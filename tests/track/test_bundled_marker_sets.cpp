// The bundled marker sets, each on a simulated subject who wears it (placement 8 mm off, segments
// 3 % off): it loads, maps onto the model, and tracks the joints it observes within a stated
// accuracy against the truth. Partial sets: the joints no marker informs are written as not
// observed (NaN), reported with the reason, and carry a large posterior uncertainty; a recording
// that shows nothing but the pelvis is refused.
#include <s2kf/app/marker_set_json.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/sim/random_sweep.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>
#include <s2kf/track/segment_observation.hpp>

#include "tracker_samples.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>
#include "address_sanitizer.hpp"

namespace {

using namespace s2kf;
namespace fs = std::filesystem;

struct SetRecording {
  sim::Recording recording;
  io::MotionTable truth;
};

/// A subject wearing `set` (the set's markers, then placement and segment-length errors) doing a
/// random sweep of every joint, 400 frames at 100 Hz.
SetRecording simulate_with(const body::MarkerSet& set, std::uint64_t seed,
                           const std::vector<sim::SegmentDropout>& dropouts = {}) {
  const body::BodyModel wearing = body::apply_marker_set(body::mmm_body_model(1000), set);
  sim::SubjectOptions options;  // defaults: placement 8 mm, segment scale 3 %, noise 0.5 mm
  options.height_mm = 1750;
  const sim::Subject subject = sim::make_subject(wearing, options, seed);
  sim::RandomSweepOptions sweep;
  sweep.duration_s = 5.0;
  const sim::KeyframeMotion motion = sim::random_sweep_motion(seed, subject.lower, subject.upper, sweep);
  sim::RecordingOptions recording_options;
  recording_options.frames = 400;
  recording_options.segment_dropouts = dropouts;
  SetRecording s;
  s.recording = sim::simulate_recording(motion, subject, recording_options, seed);
  s.truth.joint_names = subject.joint_names;
  s.truth.values.resize(s.recording.frames(), body::kRootValues + wearing.joint_count());
  for (Eigen::Index k = 0; k < s.recording.frames(); ++k) {
    s.truth.values.row(k) = body::pose_row(s.recording.truth[static_cast<std::size_t>(k)]).transpose();
    s.truth.frame.push_back(k);
    s.truth.time.push_back(s.recording.time_s(k));
  }
  return s;
}

struct SetTracked {
  pipeline::Session session;
  track::TrackingRun run;
  evaluation::TruthComparison accuracy;
  std::vector<Eigen::VectorXd> last_uncertainty;  // segment_uncertainty_deg of the last frame
};

SetTracked track_simulated(const SetRecording& s, const body::MarkerSet& set) {
  SequenceFrameSource source(s.recording);
  pipeline::SessionOptions options;
  options.tracker = track::preset_options("default", 100.0);
  options.calibration_frames = 400;
  const SampleSet& samples = test::tracker_samples(options.tracker);
  SetTracked t;
  t.session = pipeline::prepare_session(source, set, options, samples);
  pipeline::RunHooks hooks;
  io::MotionTable motion;
  motion.joint_names = t.session.model.joint_names();
  std::vector<double> rows;
  hooks.sink = [&](const track::TrackedFrame& f) {
    motion.frame.push_back(f.frame);
    motion.time.push_back(f.time);
    rows.insert(rows.end(), f.values.data(), f.values.data() + f.values.size());
    if (f.estimate && f.estimate->tracked)
      t.last_uncertainty = {track::segment_uncertainty_deg(t.session.model, t.session.segments,
                                                           f.estimate->pose.joints, f.estimate->covariance)};
  };
  t.run = pipeline::run_session(t.session, source, samples, {}, hooks);
  const Eigen::Index columns = body::kRootValues + t.session.model.joint_count();
  motion.values = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      rows.data(), static_cast<Eigen::Index>(motion.frame.size()), columns);
  t.run.motion = motion;
  t.accuracy = evaluation::compare_with_truth(t.session.model, motion, s.truth, 20);
  return t;
}

/// Every set: it applies to the model, left markers lie left of the midline and right markers
/// right of it at the zero pose, and no marker is further than 300 mm (at 1000 mm height) from the
/// joint centre of its segment (a marker on the wrong segment would be).
TEST(BundledMarkerSets, EachLoadsAndMapsOntoTheModel) {
  const std::vector<std::string> names = app::bundled_marker_set_names();
  for (const char* expected :
       {"anatomical_landmarks", "optitrack_baseline", "qualisys_animation", "qualisys_sports",
        "plugin_gait_lower", "plugin_gait_upper", "kit", "cmu", "plugin_gait"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  const body::BodyModel base = body::mmm_body_model(1000);
  const body::FrameTransforms zero = body::joint_frames(
      base, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), Eigen::VectorXd::Zero(base.joint_count()));
  for (const std::string& name : names) {
    const body::MarkerSet set = app::resolve_marker_set(name);
    EXPECT_NE(set.description.find("Source: "), std::string::npos)
        << name << ": the description names no source";
    const body::BodyModel model = body::apply_marker_set(base, set);
    ASSERT_EQ(model.marker_count(), static_cast<int>(set.entries.size())) << name;
    const Eigen::Matrix3Xd at_zero =
        body::marker_positions(model, body::Pose{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                 Eigen::VectorXd::Zero(base.joint_count())});
    for (int m = 0; m < model.marker_count(); ++m) {
      const std::string label = model.markers[static_cast<std::size_t>(m)].name;
      const double x = at_zero(0, m);
      const std::string canonical = canonical_label(label);
      const bool left = canonical[0] == 'L' && label != "L3", right = canonical[0] == 'R';
      if (left && std::abs(x) > 20) {
        EXPECT_LT(x, 0) << name << " " << label;
      }
      if (right && std::abs(x) > 20) {
        EXPECT_GT(x, 0) << name << " " << label;
      }
      const int frame = model.markers[static_cast<std::size_t>(m)].frame;
      EXPECT_LT((at_zero.col(m) - zero.origins[static_cast<std::size_t>(frame)]).norm(), 300)
          << name << " " << label;
    }
  }
}

/// Accuracy of every full-body set on its own simulated recording (the figures below are the
/// thresholds; measured values are printed): joint angles RMS over all joints, and the marker
/// distance after convergence.
TEST(BundledMarkerSets, EachTracksASimulatedRecordingOfItsOwnMarkers) {
  S2KF_SKIP_UNDER_SANITIZERS();
  for (const char* name : {"anatomical_landmarks", "optitrack_baseline", "qualisys_animation",
                           "qualisys_sports", "plugin_gait"}) {
    const body::MarkerSet set = app::resolve_marker_set(name);
    const SetRecording s = simulate_with(set, 5);
    const SetTracked t = track_simulated(s, set);
    EXPECT_EQ(t.session.markers_used(), static_cast<int>(set.entries.size())) << name;
    EXPECT_TRUE(t.session.segments.unobserved_joints.empty()) << name;
    std::cout << name << ": all-joint RMS " << t.accuracy.all_joint_rms_deg
              << " deg, segment orientation RMS " << t.accuracy.segment_orientation_rms_deg
              << " deg, worst joint " << t.accuracy.worst_joint << " " << t.accuracy.worst_joint_rms_deg
              << " deg over " << t.accuracy.frames << " frames\n";
    EXPECT_GT(t.accuracy.frames, 300) << name;
    EXPECT_LT(t.accuracy.segment_orientation_rms_deg, 12.0) << name;
    EXPECT_LT(t.accuracy.all_joint_rms_deg, 12.0) << name;
  }
}

TEST(PartialMarkerSets, LowerBodyRecordingWritesTheUpperBodyAsNotObserved) {
  const body::MarkerSet set = app::resolve_marker_set("plugin_gait_lower");
  const SetRecording s = simulate_with(set, 9);
  // The automatic choice takes the lower-body set, not the full one it is half of.
  const std::vector<body::MarkerSet> sets{app::resolve_marker_set("plugin_gait"), set};
  EXPECT_EQ(body::choose_marker_set(s.recording.labels, sets), 1);
  const SetTracked t = track_simulated(s, set);
  EXPECT_EQ(t.session.segments.unobserved_segments(),
            (std::vector<std::string>{"BP", "BT", "BLN", "BUN", "LS", "LE", "LW", "RS", "RE", "RW"}));
  bool warned = false;
  for (const std::string& w : t.session.warnings) warned = warned || w.rfind("not observed: BP, BT", 0) == 0;
  EXPECT_TRUE(warned);
  const body::BodyModel& model = t.session.model;
  for (Eigen::Index r = 20; r < t.run.motion.frames(); ++r)
    for (int j = 0; j < model.joint_count(); ++j) {
      const double v = t.run.motion.values(r, body::kRootValues + j);
      const char first = model.joints[static_cast<std::size_t>(j)].name[0];
      const bool leg = std::string(model.joints[static_cast<std::size_t>(j)].group).find_first_of("HKA") == 1;
      if (leg)
        ASSERT_TRUE(std::isfinite(v)) << model.joints[static_cast<std::size_t>(j)].name << " row " << r;
      else
        ASSERT_TRUE(std::isnan(v)) << model.joints[static_cast<std::size_t>(j)].name << " row " << r << " "
                                   << first;
    }
  std::cout << "lower body: leg joints RMS " << t.accuracy.all_joint_rms_deg << " deg, worst "
            << t.accuracy.worst_joint << " " << t.accuracy.worst_joint_rms_deg << " deg\n";
  EXPECT_LT(t.accuracy.all_joint_rms_deg, 12.0);
  // The filter knows what it does not know: the arms' angles are far less certain than the legs'.
  ASSERT_EQ(t.last_uncertainty.size(), 1u);
  const Eigen::VectorXd& sd = t.last_uncertainty[0];
  const auto at = [&](const char* segment) { return sd(t.session.segments.segment_index(segment)); };
  std::cout << "posterior SD: LK " << at("LK") << " deg, LE " << at("LE") << " deg, root " << at("root")
            << "\n";
  EXPECT_LT(at("LK"), 5.0);
  EXPECT_GT(at("LE"), 3 * at("LK"));
  EXPECT_GT(at("LS"), 3 * at("LK"));
}

TEST(PartialMarkerSets, UpperBodyRecordingWritesTheLegsAsNotObserved) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const body::MarkerSet set = app::resolve_marker_set("plugin_gait_upper");
  const SetRecording s = simulate_with(set, 13);
  const SetTracked t = track_simulated(s, set);
  EXPECT_EQ(t.session.segments.unobserved_segments(),
            (std::vector<std::string>{"LH", "LK", "LA", "RH", "RK", "RA"}));
  for (int j = 0; j < t.session.model.joint_count(); ++j) {
    const std::string& group = t.session.model.joints[static_cast<std::size_t>(j)].group;
    const bool leg = group.size() == 2 && std::string("HKA").find(group[1]) != std::string::npos;
    EXPECT_EQ(std::isnan(t.run.motion.values(100, body::kRootValues + j)), leg) << group;
  }
  EXPECT_TRUE(io::is_tracked_row(t.run.motion.values.row(100).transpose()));
  std::cout << "upper body: arm and spine joints RMS " << t.accuracy.all_joint_rms_deg << " deg\n";
  EXPECT_LT(t.accuracy.segment_orientation_rms_deg, 15.0);
}

TEST(PartialMarkerSets, CountsFramesWithoutAVisibleMarkerPerSegment) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const body::MarkerSet set = app::resolve_marker_set("plugin_gait_lower");
  const SetRecording s = simulate_with(set, 21, {sim::SegmentDropout{"LA", 1.0, 0.5}});
  const SetTracked t = track_simulated(s, set);
  const track::SegmentObservation& seen = t.run.segments;
  EXPECT_EQ(seen.frames, 400);
  EXPECT_EQ(seen.frames_without_marker[static_cast<std::size_t>(seen.segment_index("LA"))], 50);
  EXPECT_EQ(seen.frames_without_marker[static_cast<std::size_t>(seen.segment_index("RA"))], 0);
  EXPECT_EQ(seen.markers[static_cast<std::size_t>(seen.segment_index("LA"))], 3);  // LANK, LHEE, LTOE
}

TEST(PartialMarkerSets, PelvisOnlyIsRefused) {
  body::MarkerSet pelvis;
  pelvis.name = "pelvis";
  for (const char* label : {"LASI", "RASI", "LPSI", "RPSI"}) {
    body::MarkerSetEntry entry;
    entry.label = label;
    entry.like = label;
    pelvis.entries.push_back(entry);
  }
  const SetRecording s = simulate_with(pelvis, 3);
  SequenceFrameSource source(s.recording);
  pipeline::SessionOptions options;
  try {
    pipeline::prepare_session(source, pelvis, options, test::tracker_samples());
    FAIL() << "a pelvis-only recording was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("only the pelvis carries markers"), std::string::npos) << e.what();
  }
}

TEST(SegmentUncertainty, BoundedAngleSdMatchesMonteCarloAndItsLimits) {
  std::mt19937_64 rng(4);
  for (const auto& [mean, variance] :
       std::vector<std::pair<double, double>>{{0.3, 0.04}, {1.4, 0.2}, {-0.7, 1.5}}) {
    std::normal_distribution<double> theta(mean, std::sqrt(variance));
    double sum = 0, sum2 = 0;
    const int n = 400000;
    for (int i = 0; i < n; ++i) {
      const double v = 0.8 * std::sin(theta(rng));
      sum += v;
      sum2 += v * v;
    }
    const double sd = std::sqrt(sum2 / n - (sum / n) * (sum / n));
    EXPECT_NEAR(track::bounded_angle_sd(0.8, mean, variance), sd, 0.01 * sd) << mean << " " << variance;
  }
  // Small variance: the linearisation half |cos m| sqrt(v); huge variance: half / sqrt(2).
  EXPECT_NEAR(track::bounded_angle_sd(2.0, 0.5, 1e-8), 2.0 * std::cos(0.5) * 1e-4, 1e-8);
  EXPECT_NEAR(track::bounded_angle_sd(2.0, 0.5, 100.0), 2.0 / std::sqrt(2.0), 1e-9);
}

}  // namespace
