// The true-subject reference: with the subject's own skeleton and markers and nothing else wrong
// (no soft tissue, no noise) the per-frame fit must give back the true motion; with soft tissue and
// noise it is off by a little, and far less than a fit with the nominal model.
#include <s2kf/body/body_model.hpp>
#include <s2kf/sim/random_sweep.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>
#include <s2kf/track/true_subject_reference.hpp>
#include <s2kf/track/truth_metrics.hpp>

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
  const io::MotionTable fit = track::true_subject_fit(c.subject, c.recording);
  const track::TruthComparison t = track::compare_with_truth(c.subject.model, fit, truth, 0);
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
  const track::TruthComparison reference =
      track::compare_with_truth(c.subject.model, track::true_subject_fit(c.subject, c.recording), truth, 0);
  // The same fit with the nominal model of the subject's height.
  sim::Subject nominal = c.subject;
  nominal.model = body::mmm_body_model(1000).scaled(c.subject.height_mm);
  const track::TruthComparison plain =
      track::compare_with_truth(c.subject.model, track::true_subject_fit(nominal, c.recording), truth, 0);
  EXPECT_GT(reference.segment_orientation_rms_deg, 0.1);  // soft tissue and noise remain
  EXPECT_LT(reference.segment_orientation_rms_deg, 6.0);
  EXPECT_LT(reference.segment_orientation_rms_deg, 0.8 * plain.segment_orientation_rms_deg);
  EXPECT_EQ(reference.joint_limit_violations, 0);
}

TEST(TrueSubjectReference, RefusesARecordingOfAnotherMarkerSet) {
  Case c = simulate(sim::SubjectOptions{});
  c.recording.labels.back() = "XYZ";
  EXPECT_THROW(track::true_subject_fit(c.subject, c.recording), std::invalid_argument);
}

}  // namespace
