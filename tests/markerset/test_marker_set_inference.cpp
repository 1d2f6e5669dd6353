// Marker-set inference: rigid clusters from distance constancy, and a set inferred for each bundled
// recording with its labels scrambled, which must track within 1.3 times the named set's marker
// distance and joint error against the truth; recordings whose markers cannot be placed
// unambiguously are refused with a sentence that says why.
#include "address_sanitizer.hpp"
#include "test_files.hpp"
#include "tracker_samples.hpp"

#include <s2kf/app/marker_set_json.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/marker_set_mapping.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/c3d_writer.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/markerset/marker_set_inference.hpp>
#include <s2kf/markerset/rigid_clusters.hpp>
#include <s2kf/markerset/segment_rigidity.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/tracking_metrics.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

namespace {

using namespace s2kf;

using test_support::data_file;

constexpr int kSamples = 101;

markerset::MarkerSetInferenceOptions inference_options() {
  markerset::MarkerSetInferenceOptions options;
  options.tracker.samples = kSamples;
  return options;
}

/// A recording of `frames` frames at 100 Hz from a function of (frame, point) -> position.
template <typename Position>
MarkerSequence synthetic(int points, int frames, Position position) {
  MarkerSequence s;
  for (int p = 0; p < points; ++p) s.labels.push_back("p" + std::to_string(p));
  s.rate_hz = 100;
  s.resize(frames);
  for (int f = 0; f < frames; ++f) {
    for (int p = 0; p < points; ++p) s.frame(f).col(p) = position(f, p);
    s.visible.col(f).setConstant(true);
  }
  return s;
}

Eigen::Matrix3d about_z(double angle) { return body::axis_rotation(body::Axis::z, angle); }

// Two bodies of 4 points joined by a hinge, one turning up to 29 degrees either way against the
// other, and a ninth point moving on its own: three clusters, exactly the bodies; the distance SD
// within a body is the noise's, across the hinge what the frames give.
TEST(RigidClusters, FindsTheBodiesOfAHingedPair) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.5);
  const std::vector<Eigen::Vector3d> local{{100, 0, 0}, {0, 120, 0},  {0, 0, 150},  {80, 80, 40},
                                           {300, 0, 0}, {350, 60, 0}, {320, 0, 90}, {400, -50, 30}};
  const MarkerSequence s = synthetic(9, 200, [&](int f, int p) -> Eigen::Vector3d {
    const double t = f / 100.0;
    const Eigen::Vector3d drift(10 * t, 0, 0);
    const Eigen::Vector3d jitter(noise(rng), noise(rng), noise(rng));
    if (p < 4) return drift + local[static_cast<std::size_t>(p)] + jitter;
    if (p < 8) {
      const Eigen::Vector3d hinge(200, 0, 0);
      return drift + hinge + about_z(std::sin(t * 3) * 0.5) * (local[static_cast<std::size_t>(p)] - hinge) +
             jitter;
    }
    return Eigen::Vector3d(500 * std::sin(t * 7), 300 * std::cos(t * 5), 100 * t) + jitter;
  });
  const markerset::RigidClusters c = markerset::find_rigid_clusters(s, {0, 1, 2, 3, 4, 5, 6, 7, 8});
  ASSERT_EQ(c.clusters.size(), 3u);
  EXPECT_EQ(c.clusters[0], (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(c.clusters[1], (std::vector<int>{4, 5, 6, 7}));
  EXPECT_EQ(c.clusters[2], (std::vector<int>{8}));
  EXPECT_LT(c.distance_sd(0, 1), 1.0);  // noise of 0.5 mm per coordinate
  EXPECT_NEAR(c.mean_distance(0, 1), std::hypot(100.0, 120.0), 1.0);
  // Across the hinge: the SD over all frames, computed here directly, and far from rigid.
  double sum = 0, sum2 = 0;
  for (Eigen::Index f = 0; f < s.frame_count(); ++f) {
    const double d = (s.frame(f).col(0) - s.frame(f).col(5)).norm();
    sum += d, sum2 += d * d;
  }
  const double n = static_cast<double>(s.frame_count()), mean = sum / n;
  EXPECT_NEAR(c.distance_sd(0, 5), std::sqrt(sum2 / n - mean * mean), 1e-6);
  EXPECT_NEAR(c.mean_distance(0, 5), mean, 1e-9);
  EXPECT_GT(markerset::rigidity_ratio(c, 0, 5, {}), 1.0);
  EXPECT_EQ(c.cluster_of_point[6], 1);
}

struct Accuracy {
  double distance_mm = 0;
  double joint_rms_deg = 0;
  double segment_rms_deg = 0;
  std::string worst_joint;
  double worst_joint_deg = 0;
};

Accuracy track_with(const MarkerSequence& recording, const body::MarkerSet& set,
                    const io::MotionTable& truth) {
  SequenceFrameSource source(recording);
  pipeline::SessionOptions options;
  options.tracker.samples = kSamples;
  const SampleSet& samples = test::tracker_samples(kSamples);
  const pipeline::Session session = pipeline::prepare_session(source, set, options, samples);
  const track::TrackingRun run = pipeline::run_session(session, source, samples);
  const evaluation::TruthComparison truth_comparison =
      evaluation::compare_with_truth(session.model, run.motion, truth, 20);
  return {track::mean_from(run.mean_marker_distance, 20), truth_comparison.all_joint_rms_deg,
          truth_comparison.segment_orientation_rms_deg, truth_comparison.worst_joint,
          truth_comparison.worst_joint_rms_deg};
}

/// The recording `name` from frame `first` on, with its labels replaced by meaningless names in
/// shuffled order, inferred, and tracked with the named and the inferred set: every marker must
/// land on its true segment, and the inferred set must track within 1.3 times the named set's
/// marker distance and joint error (1.4 times its segment orientation error).
void expect_inferred_like_named(const std::string& name, Eigen::Index first) {
  const body::BodyModel base = body::mmm_body_model(1000);
  const MarkerSequence whole = c3d::read_c3d(data_file(name + ".c3d"));
  const MarkerSequence named = whole.frames(first, whole.frame_count() - first);
  const std::string truth_name = name == "handstand_occluded" ? "handstand" : name;
  io::MotionTable truth = io::load_motion_csv(data_file(truth_name + "_truth.csv"));
  truth.values = Eigen::MatrixXd(truth.values.bottomRows(truth.frames() - first));
  truth.frame.erase(truth.frame.begin(), truth.frame.begin() + first);
  truth.time.erase(truth.time.begin(), truth.time.begin() + first);
  MarkerSequence scrambled = named;
  std::vector<int> order(named.labels.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::shuffle(order.begin(), order.end(), std::mt19937(7));
  for (std::size_t i = 0; i < order.size(); ++i) scrambled.labels[i] = "m" + std::to_string(100 + order[i]);
  ASSERT_EQ(body::choose_marker_set(scrambled.labels, {body::model_marker_set(base)}), -1);

  const markerset::InferredMarkerSet inferred =
      markerset::infer_marker_set(scrambled, test::tracker_samples(kSamples), inference_options());
  // Where the true segment of each marker is known: how many the inference put there.
  int right_segment = 0;
  for (std::size_t i = 0; i < named.labels.size(); ++i) {
    const body::Marker& truth_marker =
        base.markers[static_cast<std::size_t>(base.marker_index(named.labels[i]))];
    const std::string expected = body::segment_of_frame(base, truth_marker.frame);
    const std::string got = body::segment_of_frame(base, base.frame_index(inferred.set.entries[i].frame));
    right_segment += expected == got ? 1 : 0;
    if (expected != got)
      std::printf("  %s: %s on %s, truly %s\n", name.c_str(), named.labels[i].c_str(), got.c_str(),
                  expected.c_str());
  }
  const Accuracy with_names = track_with(named, body::model_marker_set(base), truth);
  const Accuracy with_inferred = track_with(scrambled, inferred.set, truth);
  double worst_confidence = 1;
  for (const markerset::InferredSegment& s : inferred.segments)
    worst_confidence = std::min(worst_confidence, s.confidence);
  std::printf(
      "[inference] %s from frame %ld: %d of %zu markers on their true segment, template frame %ld, %zu "
      "clusters, "
      "%d rounds, height %.0f mm, spread %.1f mm, lowest segment confidence %.2f; marker distance %.1f "
      "(named) / "
      "%.1f (inferred) mm, all-joint RMS %.2f / %.2f deg, segment RMS %.2f / %.2f deg, worst joint %s %.1f / "
      "%s "
      "%.1f deg\n",
      name.c_str(), static_cast<long>(first), right_segment, named.labels.size(), inferred.template_frame,
      inferred.clusters.clusters.size(), inferred.rounds, inferred.height_mm, inferred.spread_mm,
      worst_confidence, with_names.distance_mm, with_inferred.distance_mm, with_names.joint_rms_deg,
      with_inferred.joint_rms_deg, with_names.segment_rms_deg, with_inferred.segment_rms_deg,
      with_names.worst_joint.c_str(), with_names.worst_joint_deg, with_inferred.worst_joint.c_str(),
      with_inferred.worst_joint_deg);
  for (const std::string& note : inferred.notes) std::printf("  %s\n", note.c_str());
  EXPECT_EQ(right_segment, static_cast<int>(named.labels.size())) << name;
  EXPECT_LE(with_inferred.distance_mm, 1.3 * with_names.distance_mm) << name;
  EXPECT_LE(with_inferred.joint_rms_deg, 1.3 * with_names.joint_rms_deg) << name;
  // Segment orientations within 1.4 times, not 1.3: with every marker on its true segment, only
  // the offsets differ (the template frame's, not the model's), and the calibration carries that
  // difference into the weakly identified axial angles (docs/calibration.md, the gauges).
  EXPECT_LE(with_inferred.segment_rms_deg, 1.4 * with_names.segment_rms_deg) << name;
}

// Every bundled recording (simulated subjects wearing the model's 50 markers) with its labels
// scrambled: no bundled set matches, and the inferred set tracks like the named one.
TEST(MarkerSetInference, ScrambledBundledRecordingsTrackLikeTheNamedSet) {
  S2KF_SKIP_UNDER_SANITIZERS();
  for (const char* name : {"walk", "cartwheel", "handstand", "handstand_occluded"})
    expect_inferred_like_named(name, 0);
}

// A recording that does not start standing: the walk cut to start mid-stride (frame 100). The
// template frame is found later in the recording, and the set is as good as from a standing start.
TEST(MarkerSetInference, ARecordingThatDoesNotStartStanding) {
  S2KF_SKIP_UNDER_SANITIZERS();
  expect_inferred_like_named("walk", 100);
}

// The inference on two threads (the template fits and the attempts side by side) gives the set it
// gives on one, to the bit: each piece writes only its own result, and they are compared in order.
TEST(MarkerSetInference, TheSameSetOnOneThreadAndOnTwo) {
  S2KF_SKIP_UNDER_SANITIZERS();
  MarkerSequence scrambled = c3d::read_c3d(data_file("walk.c3d"));
  for (std::size_t i = 0; i < scrambled.labels.size(); ++i)
    scrambled.labels[i] = "m" + std::to_string(100 + (i * 7) % scrambled.labels.size());
  markerset::MarkerSetInferenceOptions options = inference_options();
  options.threads = 1;
  const markerset::InferredMarkerSet one =
      markerset::infer_marker_set(scrambled, test::tracker_samples(kSamples), options);
  options.threads = 2;
  const markerset::InferredMarkerSet two =
      markerset::infer_marker_set(scrambled, test::tracker_samples(kSamples), options);
  EXPECT_EQ(one.template_frame, two.template_frame);
  EXPECT_EQ(one.rounds, two.rounds);
  EXPECT_EQ(one.height_mm, two.height_mm);
  ASSERT_EQ(one.set.entries.size(), two.set.entries.size());
  for (std::size_t i = 0; i < one.set.entries.size(); ++i) {
    EXPECT_EQ(one.set.entries[i].frame, two.set.entries[i].frame) << one.set.entries[i].label;
    EXPECT_EQ(one.set.entries[i].offset, two.set.entries[i].offset) << one.set.entries[i].label;
  }
}

// The topology check on the simulated cartwheel: with the true assignment it moves nothing; with a
// thigh marker put on the hand (what a template fit does where the hand hangs beside the thigh) it
// moves it back to the thigh; with a hand marker put on the thigh it moves it to the hand or the
// forearm (the cartwheel hardly turns the wrist, so both are rigid with it, and only the template
// can tell them apart); and nothing else moves.
TEST(SegmentRigidity, RepairsAThighMarkerOnTheHandAndAHandMarkerOnTheThigh) {
  const body::BodyModel base = body::mmm_body_model(1000);
  const MarkerSequence recording = c3d::read_c3d(data_file("cartwheel.c3d"));
  std::vector<int> points, truth;
  for (std::size_t p = 0; p < recording.labels.size(); ++p) {
    points.push_back(static_cast<int>(p));
    truth.push_back(base.markers[static_cast<std::size_t>(base.marker_index(recording.labels[p]))].frame);
  }
  const markerset::RigidClusters clusters = markerset::find_rigid_clusters(recording, points);
  std::vector<int> frame_of = truth;
  EXPECT_TRUE(markerset::repair_segment_assignment(clusters, base, points, frame_of).empty());
  EXPECT_EQ(frame_of, truth);

  const auto point_of = [&](const std::string& label) {
    return static_cast<std::size_t>(std::find(recording.labels.begin(), recording.labels.end(), label) -
                                    recording.labels.begin());
  };
  struct Case {
    std::string label, wrong;
    std::vector<std::string> right;  // the segments it may land on
  };
  for (const Case& c : {Case{"LTHI", "LW", {"LH"}}, Case{"LHTS", "LH", {"LW", "LE"}}}) {
    const std::string& label = c.label;
    const std::size_t marker = point_of(label);
    frame_of = truth;
    frame_of[marker] = base.frame_index(c.wrong);
    const std::vector<markerset::MarkerRigidity> before =
        markerset::marker_rigidity(clusters, base, points, frame_of);
    const std::vector<markerset::SegmentMove> moves =
        markerset::repair_segment_assignment(clusters, base, points, frame_of);
    for (const markerset::SegmentMove& m : moves)
      std::printf("[rigidity] moved %s from %s to %s (median distance SD %.1f -> %.1f mm)\n",
                  recording.labels[m.marker].c_str(), m.from.c_str(), m.to.c_str(), m.from_sd_mm, m.to_sd_mm);
    EXPECT_GT(before[marker].own_sd_mm, 20.0) << label;  // centimetres against the wrong segment's markers
    ASSERT_EQ(moves.size(), 1u) << label;
    EXPECT_EQ(moves[0].marker, marker);
    const std::string landed = body::segment_of_frame(base, frame_of[marker]);
    EXPECT_NE(std::find(c.right.begin(), c.right.end(), landed), c.right.end()) << label << " on " << landed;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (i != marker) {
        EXPECT_EQ(frame_of[i], truth[i]) << recording.labels[i];
      }
    }
  }
}

std::string refusal(const MarkerSequence& recording) {
  try {
    markerset::infer_marker_set(recording, test::tracker_samples(kSamples), inference_options());
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// Ten markers on one rigid object that moves and turns: nothing tells one segment from another.
TEST(MarkerSetInference, RefusesOneRigidCluster) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> place(-200, 200);
  std::vector<Eigen::Vector3d> local(10);
  for (Eigen::Vector3d& l : local) l = Eigen::Vector3d(place(rng), place(rng), place(rng) + 900);
  const MarkerSequence s = synthetic(10, 200, [&](int f, int p) -> Eigen::Vector3d {
    return Eigen::Vector3d(3.0 * f, 0, 0) + about_z(0.01 * f) * local[static_cast<std::size_t>(p)];
  });
  const std::string why = refusal(s);
  EXPECT_NE(why.find("one rigid cluster"), std::string::npos) << why;
}

// Two stacked rings of markers, each round a vertical axis, turning against each other: two
// rigid clusters, but nothing says which way the "body" faces.
TEST(MarkerSetInference, RefusesWhenTheFacingDirectionIsAmbiguous) {
  const MarkerSequence s = synthetic(16, 200, [&](int f, int p) -> Eigen::Vector3d {
    const double angle = 2 * kPi * (p % 8) / 8.0;
    const Eigen::Vector3d ring(150 * std::cos(angle), 150 * std::sin(angle), p < 8 ? 900.0 : 1400.0);
    return about_z(p < 8 ? 0.0 : 1.5 * std::sin(f / 20.0)) * ring;
  });
  const std::string why = refusal(s);
  EXPECT_NE(why.find("ambiguous"), std::string::npos) << why;
}

// Markers that move independently of each other, about a standing subject's places: no body
// model fits them, and the sentence says what failed.
TEST(MarkerSetInference, RefusesMarkersThatMoveIndependently) {
  const body::BodyModel base = body::mmm_body_model(1750);
  const Eigen::Matrix3Xd standing = body::marker_positions(base, body::zero_pose(base));
  const MarkerSequence s = synthetic(base.marker_count(), 300, [&](int f, int p) -> Eigen::Vector3d {
    const double t = f / 100.0, phase = 0.7 * p;
    return standing.col(p) + 150 * Eigen::Vector3d(std::sin(3 * t + phase), std::cos(2.3 * t + 2 * phase),
                                                   0.5 * std::sin(1.7 * t + 3 * phase));
  });
  const std::string why = refusal(s);
  EXPECT_NE(why.find("give a marker set (--markerset)"), std::string::npos) << why;
  std::printf("[inference] independent markers refused: %s\n", why.c_str());
}

}  // namespace
