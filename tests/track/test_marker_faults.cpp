// Labelling faults real recordings have, injected into a simulated recording with its true motion:
// a stuck marker, two labels swapped for a while, and ghost jumps. The tracker's per-marker gate
// (an innovation improbable under the marker's predicted covariance) and its frozen-marker check
// must find them, leave them out, count them, and keep the pose close to the clean recording's.
#include "test_files.hpp"
#include "tracker_samples.hpp"

#include <s2kf/core/constants.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/pipeline/session.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include "address_sanitizer.hpp"

namespace {

using namespace s2kf;

constexpr Eigen::Index kRecordingFrames = 400;
constexpr long kWarmup = 20;

using test_support::data_file;

struct Outcome {
  evaluation::TruthComparison truth;
  track::TrackingRun run;
  body::BodyModel model;
};

struct Walk {
  MarkerSequence clean = c3d::read_c3d(data_file("walk.c3d")).frames(0, kRecordingFrames);
  io::MotionTable truth = io::load_motion_csv(data_file("walk_truth.csv"));
  double height_mm = 0;

  Eigen::Index point(const std::string& label) const {
    const auto at = std::find(clean.labels.begin(), clean.labels.end(), label);
    EXPECT_NE(at, clean.labels.end()) << label;
    return at - clean.labels.begin();
  }

  // Tracks without calibration (the faults are the subject here), the height fixed to the clean
  // recording's estimate so that every run uses the same model.
  Outcome track(const MarkerSequence& recording, bool guard, pipeline::SessionOptions options = {}) {
    options.calibrate = false;
    options.height_mm = height_mm;
    if (!guard) {
      options.tracker.marker_gate_probability = 0;
      options.tracker.frozen_marker_s = 0;
    }
    SequenceFrameSource source(recording);
    const body::BodyModel base = body::mmm_body_model(1000);
    const pipeline::Session session =
        pipeline::prepare_session(source, body::model_marker_set(base), options, test::tracker_samples());
    if (height_mm == 0) height_mm = session.height_mm;
    Outcome outcome{{}, pipeline::run_session(session, source, test::tracker_samples()), session.model};
    outcome.truth = evaluation::compare_with_truth(session.model, outcome.run.motion, truth, kWarmup);
    return outcome;
  }

  long rejected(const Outcome& o, const std::string& label, bool frozen) const {
    const auto names = o.model.marker_names();
    const auto m = static_cast<std::size_t>(std::find(names.begin(), names.end(), label) - names.begin());
    return (frozen ? o.run.rejected_as_frozen : o.run.rejected_by_innovation).at(m);
  }
};

// The figures of the fault table in docs/faults.md.
void report(const char* fault, const Outcome& clean, const Outcome& guarded, const Outcome& open) {
  std::printf(
      "[fault] %s: segment RMS %.2f / %.2f / %.2f deg, limb flexion %.2f / %.2f / %.2f deg "
      "(clean / guarded / unguarded)\n",
      fault, clean.truth.segment_orientation_rms_deg, guarded.truth.segment_orientation_rms_deg,
      open.truth.segment_orientation_rms_deg, clean.truth.limb_flexion_rms_deg,
      guarded.truth.limb_flexion_rms_deg, open.truth.limb_flexion_rms_deg);
}

long total(const std::vector<long>& counts) {
  long sum = 0;
  for (long c : counts) sum += c;
  return sum;
}

TEST(MarkerFaults, CleanRecordingLosesNothingToTheGate) {
  S2KF_SKIP_UNDER_SANITIZERS();
  Walk walk;
  const Outcome guarded = walk.track(walk.clean, true);
  const Outcome open = walk.track(walk.clean, false);
  report("none", guarded, guarded, open);
  // Hardly any of the 400 x 50 marker observations is left out, and the pose is unchanged.
  EXPECT_LT(total(guarded.run.rejected_by_innovation), kRecordingFrames * 50 / 200);
  EXPECT_EQ(total(guarded.run.rejected_as_frozen), 0);
  EXPECT_LT(guarded.truth.segment_orientation_rms_deg, open.truth.segment_orientation_rms_deg * 1.05 + 0.1);
}

TEST(MarkerFaults, AStuckWristMarkerIsLeftOutAsFrozen) {
  S2KF_SKIP_UNDER_SANITIZERS();
  Walk walk;
  const Outcome clean = walk.track(walk.clean, true);
  MarkerSequence stuck = walk.clean;
  const Eigen::Index p = walk.point("RWTS");
  for (Eigen::Index f = 100; f < kRecordingFrames; ++f)
    stuck.positions.block<3, 1>(3 * p, f) = stuck.positions.block<3, 1>(3 * p, 100);
  const Outcome guarded = walk.track(stuck, true);
  const Outcome open = walk.track(stuck, false);
  // Frozen from frame 110 on (0.1 s at 100 Hz): every later frame is left out.
  report("stuck wrist marker", clean, guarded, open);
  EXPECT_GE(walk.rejected(guarded, "RWTS", true), kRecordingFrames - 112);
  EXPECT_LT(guarded.truth.segment_orientation_rms_deg, clean.truth.segment_orientation_rms_deg * 1.2 + 0.3);
  EXPECT_GT(open.truth.segment_orientation_rms_deg, guarded.truth.segment_orientation_rms_deg);
}

TEST(MarkerFaults, SwappedKneeLabelsAreLeftOutByTheirInnovation) {
  S2KF_SKIP_UNDER_SANITIZERS();
  Walk walk;
  const Outcome clean = walk.track(walk.clean, true);
  MarkerSequence swapped = walk.clean;
  const Eigen::Index left = walk.point("LKNE"), right = walk.point("RKNE");
  for (Eigen::Index f = 150; f < 250; ++f)
    swapped.positions.block<3, 1>(3 * left, f).swap(swapped.positions.block<3, 1>(3 * right, f));
  const Outcome guarded = walk.track(swapped, true);
  const Outcome open = walk.track(swapped, false);
  report("knee labels swapped for 1 s", clean, guarded, open);
  EXPECT_GE(walk.rejected(guarded, "LKNE", false), 90);
  EXPECT_GE(walk.rejected(guarded, "RKNE", false), 90);
  EXPECT_LT(guarded.truth.limb_flexion_rms_deg, clean.truth.limb_flexion_rms_deg * 1.2 + 0.3);
  EXPECT_GT(open.truth.limb_flexion_rms_deg, guarded.truth.limb_flexion_rms_deg);
}

TEST(MarkerFaults, GhostJumpsAreLeftOut) {
  S2KF_SKIP_UNDER_SANITIZERS();
  Walk walk;
  const Outcome clean = walk.track(walk.clean, true);
  MarkerSequence ghosts = walk.clean;
  const Eigen::Index p = walk.point("LANK");
  long jumps = 0;
  for (Eigen::Index f = 50; f < kRecordingFrames; f += 25, ++jumps) ghosts.positions(3 * p + 2, f) += 300.0;
  const Outcome guarded = walk.track(ghosts, true);
  report("ghost jumps of 300 mm", clean, guarded, walk.track(ghosts, false));
  EXPECT_EQ(walk.rejected(guarded, "LANK", false), jumps);
  EXPECT_LT(guarded.truth.all_joint_rms_deg, clean.truth.all_joint_rms_deg * 1.05 + 0.1);
}

}  // namespace

// The stacked twists of the spine (BPz, BTz) and the neck (BLNz, BUNz) are seen only through their
// sums. With the pseudo-measurement that splits each sum evenly, a change far below the noise in
// the input (0.0005 mm on every coordinate of one frame) changes them by a tiny amount, not tens of
// degrees, and the two angles of a pair stay close.
TEST(UnobservableTwists, ATinyInputChangeMakesATinyChange) {
  S2KF_SKIP_UNDER_SANITIZERS();
  Walk walk;
  walk.track(walk.clean, true);  // fixes the height
  const Outcome reference = walk.track(walk.clean, true);
  MarkerSequence nudged = walk.clean;
  nudged.positions.col(60).array() += 0.0005;
  const Outcome changed = walk.track(nudged, true);
  pipeline::SessionOptions no_split;
  no_split.tracker.axial_split_sd_rad = 0;
  const Outcome free_reference = walk.track(walk.clean, true, no_split);
  const Outcome free_changed = walk.track(nudged, true, no_split);
  const std::vector<std::string> joints = reference.model.joint_names();
  for (const std::string name : {"BPz", "BTz", "BLNz", "BUNz"}) {
    const auto j = 6 + (std::find(joints.begin(), joints.end(), name) - joints.begin());
    const double change =
        (reference.run.motion.values.col(j) - changed.run.motion.values.col(j)).cwiseAbs().maxCoeff();
    const double free_change =
        (free_reference.run.motion.values.col(j) - free_changed.run.motion.values.col(j))
            .cwiseAbs()
            .maxCoeff();
    std::printf("[twist] %s: largest change %.4f deg with the even split, %.4f deg without\n", name.c_str(),
                change * kDegreesPerRadian, free_change * kDegreesPerRadian);
    // Measured: 0.0000 deg in the portable build, 0.004-0.025 deg in a -march=native build on an
    // AVX-512 machine, where the nudge flips one discrete decision of the run (translation moves
    // by 1.2 mm, observed joints by up to 0.09 deg); without the split 0.05-7.5 deg.
    EXPECT_LT(change * kDegreesPerRadian, 0.05) << name;
  }
  const auto column = [&](const char* name) {
    return reference.run.motion.values.col(6 +
                                           (std::find(joints.begin(), joints.end(), name) - joints.begin()));
  };
  const double split = (column("BPz") - column("BTz")).cwiseAbs().tail(kRecordingFrames - kWarmup).maxCoeff();
  EXPECT_LT(split * kDegreesPerRadian, 10.0);
}
