// The subject calibration judged by the joints against the truth: the gauge directions the
// bundle adjustment finds from the model, and the target (calibration never makes the
// segments or the limb flexion worse than no calibration) on the bundled synthetic recordings
// (data/*.c3d with data/*_truth.csv) and simulated realistic subjects, tracked as `s2kf track`
// tracks them. Where the target is not met (the cartwheel, a simulated subject's limb flexion) the
// tests hold what is true now, so that it cannot get worse unseen.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/sim/random_sweep.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>
#include <s2kf/track/tracking_run.hpp>

#include "address_sanitizer.hpp"
#include "sweep_recording.hpp"
#include "tracker_samples.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>

namespace {

using namespace s2kf;

/// Tracks `recording` as `s2kf track` does with the model's own marker set (the KIT markers all
/// these recordings carry), calibrated or not, and compares the motion with the truth after 20
/// frames.
evaluation::TruthComparison track_against_truth(const MarkerSequence& recording, const io::MotionTable& truth,
                                                bool calibrate, double prior_only_fraction) {
  pipeline::SessionOptions options;
  options.calibrate = calibrate;
  options.calibration.prior_only_fraction = prior_only_fraction;
  const SampleSet& samples = test::tracker_samples(options.tracker);
  SequenceFrameSource source(recording);
  const pipeline::Session session =
      pipeline::prepare_session(source, body::model_marker_set(body::mmm_body_model(1000)), options, samples);
  SequenceFrameSource again(recording);
  const track::TrackingRun run = pipeline::run_session(session, again, samples, {});
  return evaluation::compare_with_truth(session.model, run.motion, truth, 20);
}

/// No calibration, the default calibration, and the gauge-aware one (prior_only_fraction 0.3).
struct Verdict {
  evaluation::TruthComparison plain, calibrated, gauge_aware;
};

Verdict compare(const std::string& name, const MarkerSequence& recording, const io::MotionTable& truth) {
  Verdict v{
      track_against_truth(recording, truth, false, 0),
      track_against_truth(recording, truth, true, calibration::CalibrationOptions{}.prior_only_fraction),
      track_against_truth(recording, truth, true, 0.3)};
  std::printf(
      "%s: segments %.2f / %.2f / %.2f deg, limb flexion %.2f / %.2f / %.2f deg (no calibration / "
      "calibrated / gauge-aware)\n",
      name.c_str(), v.plain.segment_orientation_rms_deg, v.calibrated.segment_orientation_rms_deg,
      v.gauge_aware.segment_orientation_rms_deg, v.plain.limb_flexion_rms_deg,
      v.calibrated.limb_flexion_rms_deg, v.gauge_aware.limb_flexion_rms_deg);
  return v;
}

// Calibration is judged to be no worse when it stays within this of no calibration (the runs are
// deterministic; the margin keeps the test from failing on a change of rounding).
constexpr double kMarginDeg = 0.05;

// The target: calibrating never makes the segments or the limb flexion worse than no
// calibration.
void expect_not_worse_than_no_calibration(const Verdict& v) {
  EXPECT_LE(v.calibrated.segment_orientation_rms_deg, v.plain.segment_orientation_rms_deg + kMarginDeg);
  EXPECT_LE(v.calibrated.limb_flexion_rms_deg, v.plain.limb_flexion_rms_deg + kMarginDeg);
  EXPECT_EQ(v.calibrated.joint_limit_violations, 0);
}

Verdict compare_bundled(const std::string& name) {
  const std::string base = std::string(S2KF_DATA_DIR) + "/" + name;
  const MarkerSequence recording = c3d::read_c3d(base + ".c3d");
  return compare(name, recording, io::load_motion_csv(base + "_truth.csv"));
}

// Met on these three since the tracker keeps joints off the sine's turning point at their limits
// (measured, segments without / with calibration: walk 6.04 / 5.88 deg (before: 7.17 / 8.45),
// handstand 10.33 / 9.43, occluded handstand 14.71 / 11.66; limb flexion 2.73 / 2.09, 2.89 / 2.78,
// 4.60 / 3.41). Not yet on the cartwheel (below).
class CalibrationMet : public ::testing::TestWithParam<const char*> {};

TEST_P(CalibrationMet, CalibrationDoesNotMakeTheJointsWorse) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const std::string base = std::string(S2KF_DATA_DIR) + "/" + GetParam();
  const MarkerSequence recording = c3d::read_c3d(base + ".c3d");
  const io::MotionTable truth = io::load_motion_csv(base + "_truth.csv");
  Verdict v;
  v.plain = track_against_truth(recording, truth, false, 0);
  v.calibrated =
      track_against_truth(recording, truth, true, calibration::CalibrationOptions{}.prior_only_fraction);
  expect_not_worse_than_no_calibration(v);
}

INSTANTIATE_TEST_SUITE_P(CalibrationAccuracy, CalibrationMet,
                         ::testing::Values("walk", "handstand", "handstand_occluded"));

// Not met on the cartwheel: calibrating costs it about a degree (measured: segments 10.36 -> 11.37
// deg, limb flexion 4.51 -> 5.70, no calibration -> calibrated); held within 1.5 degrees so the gap
// cannot grow unseen. (The walk and both handstands meet the target: CalibrationMet above.)
TEST(CalibrationAccuracy, CalibratingTheCartwheelCostsLessThanOneAndAHalfDegrees) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const Verdict v = compare_bundled("cartwheel");
  EXPECT_GT(v.calibrated.segment_orientation_rms_deg, v.plain.segment_orientation_rms_deg);  // still not met
  EXPECT_LE(v.calibrated.segment_orientation_rms_deg, v.plain.segment_orientation_rms_deg + 1.5);
  EXPECT_LE(v.calibrated.limb_flexion_rms_deg, v.plain.limb_flexion_rms_deg + 1.5);
  EXPECT_EQ(v.calibrated.joint_limit_violations, 0);
}

/// A simulated realistic subject (the simulator's defaults: 8 mm placement SD fixed on the
/// segments, 3 % bone lengths, 8 mm pose-dependent soft tissue) moving through a random sweep of
/// its joints.
struct Simulated {
  sim::Recording recording;
  io::MotionTable truth;
};

Simulated simulated(std::uint64_t seed) {
  const sim::Subject subject = sim::make_subject(body::mmm_body_model(1750), sim::SubjectOptions{}, seed);
  Simulated s{test_support::sweep_recording(subject, seed, 700, 8.0), {}};
  s.truth = sim::truth_motion(s.recording, body::mmm_body_model(1750).joint_names());
  return s;
}

// Calibrates a subject without soft tissue moving through all its joints (random sweep, 400
// frames) with `options`, and checks that the directions left to the prior are exactly the ones the
// kinematics cannot see: each foot's markers turned about the 3-DoF ankle (3 each), the head's about
// the 3-DoF neck (3) and each hand's about the wrist's free axis (1 each), 11 in all.
void expect_the_model_gauges(calibration::CalibrationOptions options, const char* criterion) {
  sim::SubjectOptions without_soft_tissue;
  without_soft_tissue.soft_tissue_mm = 0;
  const sim::Subject subject = sim::make_subject(body::mmm_body_model(1750), without_soft_tissue, 7);
  const sim::Recording recording = test_support::sweep_recording(subject, 7, 400, 5.0);
  const body::BodyModel model = body::mmm_body_model(1750);
  track::TrackerOptions tracker;
  tracker.samples = 101;
  options.final_pass = false;
  const calibration::SubjectCalibration calibration =
      calibration::calibrate_subject(model, body::map_markers(recording.labels, model.marker_names()),
                                     tracker, recording, test::tracker_samples(tracker), options);
  std::map<std::string, int> count;
  for (const auto& d : calibration.passes.front().prior_only) {
    std::printf("prior only (%s): %s, ratio %.2g, segment share %.0f %%\n", criterion, d.segment.c_str(),
                d.information_ratio, 100 * d.share);
    ++count[d.segment];
  }
  EXPECT_EQ(count["LA"], 3) << criterion;
  EXPECT_EQ(count["RA"], 3) << criterion;
  EXPECT_EQ(count["BUN"], 3) << criterion;
  EXPECT_EQ(count["LW"], 1) << criterion;
  EXPECT_EQ(count["RW"], 1) << criterion;
  EXPECT_EQ(calibration.passes.front().prior_only.size(), 11u) << criterion;
}

// The gauge directions found from the model: the directions whose data information is below 1e-5
// of a marker coordinate's seen in every frame (below 1e-3 of the prior's).
TEST(CalibrationAccuracy, FindsTheGaugeDirectionsOfTheModel) {
  S2KF_SKIP_UNDER_SANITIZERS();
  calibration::CalibrationOptions options;
  options.prior_only_fraction = 1e-5;
  expect_the_model_gauges(options, "information ratio");
}

// The share criterion (prior_only_share) finds the same gauges: the 11 directions the kinematics
// cannot see keep (almost) none of their information through the poses' elimination, and every
// other direction keeps more than 1e-4 of it.
TEST(CalibrationAccuracy, TheShareCriterionFindsTheSameGaugeDirections) {
  S2KF_SKIP_UNDER_SANITIZERS();
  calibration::CalibrationOptions options;
  options.prior_only_share = true;
  options.prior_only_fraction = 1e-4;
  options.bundle_iterations = 1;  // the directions are chosen at the first linearisation
  expect_the_model_gauges(options, "surviving share");
}

// On a simulated realistic subject (seed 3) calibrating brings the segments from 8.05 to 6.23
// degrees but limb flexion from 3.36 to 3.78 (seed 5: 7.71 -> 5.40 and 3.78 -> 2.86): the segments
// gain over a degree, flexion loses under 0.6 (the target, flexion no worse, is not met on seed 3).
TEST(CalibrationAccuracy, OnASimulatedSubjectTheSegmentsGainAndFlexionLosesLittle) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const Simulated s = simulated(3);
  const Verdict v = compare("simulated seed 3", s.recording, s.truth);
  EXPECT_LT(v.calibrated.segment_orientation_rms_deg, v.plain.segment_orientation_rms_deg - 1.0);
  EXPECT_LE(v.calibrated.limb_flexion_rms_deg, v.plain.limb_flexion_rms_deg + 0.6);
  EXPECT_EQ(v.calibrated.joint_limit_violations, 0);
}

}  // namespace
