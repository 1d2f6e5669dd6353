// The true-subject reference: with the subject's own skeleton and markers and nothing else wrong
// (no soft tissue, no noise) the per-frame fit must give back the true motion; with soft tissue and
// noise it is off by a little, and far less than a fit with the nominal model.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/evaluation/true_subject_reference.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/sim/random_sweep.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

#include <gtest/gtest.h>

namespace {

using namespace s2kf;

struct Case {
  sim::Subject subject;
  sim::Recording recording;
};

Case simulate(const sim::SubjectOptions& options) {
  Case c{sim::make_subject(body::mmm_body_model(1000), options, 4), {}};
  sim::RandomSweepOptions sweep;
  sweep.duration_s = 2;
  const sim::KeyframeMotion motion = sim::random_sweep_motion(4, c.subject.lower, c.subject.upper, sweep);
  sim::RecordingOptions recording;
  recording.frames = 60;
  c.recording = sim::simulate_recording(motion, c.subject, recording, 4);
  return c;
}

TEST(TrueSubjectReference, RecoversTheTruthWhenOnlyTheSubjectDiffersFromTheModel) {
  sim::SubjectOptions options;  // placement and bone lengths as drawn, nothing moving the markers
  options.soft_tissue_mm = 0;
  options.noise_sd_mm = 0;
  const Case c = simulate(options);
  const io::MotionTable truth = sim::truth_motion(c.recording, c.subject.joint_names);
  const io::MotionTable fit = evaluation::true_subject_fit(c.subject, c.recording);
  const evaluation::TruthComparison t = evaluation::compare_with_truth(c.subject.model, fit, truth, 0);
  EXPECT_EQ(t.frames, 60);
  EXPECT_LT(t.root_position_rms_mm, 1e-3);
  EXPECT_LT(t.root_orientation_rms_deg, 1e-3);
  // The redundant spine and neck pairs move no marker apart; the segments the markers ride on must
  // come out exact.
  EXPECT_LT(t.segment_orientation_rms_deg, 1e-3);
}

TEST(TrueSubjectReference, IsBetterThanTheNominalModelOnARealisticSubject) {
  const Case c = simulate(sim::SubjectOptions{});
  const io::MotionTable truth = sim::truth_motion(c.recording, c.subject.joint_names);
  const evaluation::TruthComparison reference = evaluation::compare_with_truth(
      c.subject.model, evaluation::true_subject_fit(c.subject, c.recording), truth, 0);
  // The same fit with the nominal model of the subject's height.
  sim::Subject nominal = c.subject;
  nominal.model = body::mmm_body_model(1000).scaled(c.subject.height_mm);
  const evaluation::TruthComparison plain = evaluation::compare_with_truth(
      c.subject.model, evaluation::true_subject_fit(nominal, c.recording), truth, 0);
  EXPECT_GT(reference.segment_orientation_rms_deg, 0.1);  // soft tissue and noise remain
  EXPECT_LT(reference.segment_orientation_rms_deg, 6.0);
  EXPECT_LT(reference.segment_orientation_rms_deg, 0.8 * plain.segment_orientation_rms_deg);
  EXPECT_EQ(reference.joint_limit_violations, 0);
}

TEST(TrueSubjectReference, RefusesARecordingOfAnotherMarkerSet) {
  Case c = simulate(sim::SubjectOptions{});
  c.recording.labels.back() = "XYZ";
  EXPECT_THROW(evaluation::true_subject_fit(c.subject, c.recording), std::invalid_argument);
  EXPECT_THROW(evaluation::best_constant_placement(c.subject, c.recording), std::invalid_argument);
}

TEST(BestConstantPlacement, IsThePlacementWhenNothingMovesTheMarkers) {
  sim::SubjectOptions options;
  options.soft_tissue_mm = 0;
  options.noise_sd_mm = 0;
  Case c = simulate(options);
  // Hide one marker in half the frames: the mean over the frames that show it is the same.
  for (Eigen::Index k = 0; k < c.recording.frames(); k += 2) c.recording.visible(3, k) = false;
  const sim::Subject constant = evaluation::best_constant_placement(c.subject, c.recording);
  for (std::size_t m = 0; m < constant.model.markers.size(); ++m)
    EXPECT_LT((constant.model.markers[m].offset - c.subject.model.markers[m].offset).norm(), 1e-9) << m;
  EXPECT_EQ(constant.model.joints.size(), c.subject.model.joints.size());
}

TEST(BestConstantPlacement, TakesTheMeanOfTheMarkerInItsSegmentFrame) {
  sim::SubjectOptions options;
  options.soft_tissue_mm = 0;
  options.noise_sd_mm = 0;
  Case c = simulate(options);
  // Move marker 5 by +d in its segment's frame in the even frames and -3d in the odd ones (60
  // frames, 30 of each): its mean moves by -d; every other marker stays.
  const Eigen::Vector3d d(4, -2, 6);
  const int frame = c.subject.model.markers[5].frame;
  for (Eigen::Index k = 0; k < c.recording.frames(); ++k) {
    const body::FrameTransforms tf =
        body::joint_frames(c.subject.model, c.recording.truth[static_cast<std::size_t>(k)]);
    const Eigen::Vector3d shift =
        tf.rotations[static_cast<std::size_t>(frame)] * (k % 2 == 0 ? d : Eigen::Vector3d(-3 * d));
    c.recording.positions.block<3, 1>(3 * 5, k) += shift;
  }
  const sim::Subject constant = evaluation::best_constant_placement(c.subject, c.recording);
  EXPECT_LT((constant.model.markers[5].offset - (c.subject.model.markers[5].offset - d)).norm(), 1e-9);
  EXPECT_LT((constant.model.markers[6].offset - c.subject.model.markers[6].offset).norm(), 1e-9);
}

TEST(BestConstantPlacement, FitsARealisticSubjectBetterThanItsTruePlacement) {
  // Soft tissue's average over the recording is part of where the markers sit: fitted with it, the
  // per-frame fit is closer to the true motion than with the placement alone.
  const Case c = simulate(sim::SubjectOptions{});
  const io::MotionTable truth = sim::truth_motion(c.recording, c.subject.joint_names);
  const evaluation::TruthComparison placement = evaluation::compare_with_truth(
      c.subject.model, evaluation::true_subject_fit(c.subject, c.recording), truth, 0);
  const evaluation::TruthComparison constant = evaluation::compare_with_truth(
      c.subject.model,
      evaluation::true_subject_fit(evaluation::best_constant_placement(c.subject, c.recording), c.recording),
      truth, 0);
  EXPECT_GT(constant.segment_orientation_rms_deg, 0.1);  // the soft tissue's changes remain
  EXPECT_LT(constant.segment_orientation_rms_deg, placement.segment_orientation_rms_deg);
}

}  // namespace
