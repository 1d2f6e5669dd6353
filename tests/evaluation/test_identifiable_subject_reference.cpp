// The identifiable-subject reference: the true subject with the part no calibration can determine
// reset to the nominal. Checked in closed form on a subject whose difference from the nominal is
// known: a foot's markers turned about the 3-DoF ankle (a gauge: a constant ankle-angle offset
// undoes it) must come back to the nominal, a thigh marker moved and a thigh made longer (both
// seen by the data while the knee bends) must stay the true subject's.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/evaluation/identifiable_subject_reference.hpp>
#include <s2kf/evaluation/true_subject_reference.hpp>
#include <s2kf/sim/random_sweep.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace {

using namespace s2kf;

constexpr double kNoiseMm = 10.0;  // the tracker's marker noise, the information's metric
// The exact-gauge threshold (CalibrationOptions::prior_only_fraction's units): on this subject the
// 11 gauges lie below 2e-6 of a seen marker coordinate's information, the next direction at 5e-5.
constexpr double kExactGauges = 1e-5;

struct GaugeCase {
  sim::Subject subject;
  sim::Recording recording;
  std::vector<long> frames;  // the calibration frames
};

GaugeCase simulate_sweep(double soft_tissue_mm) {
  sim::SubjectOptions options;
  options.soft_tissue_mm = soft_tissue_mm;
  GaugeCase c{sim::make_subject(body::mmm_body_model(1750), options, 7), {}, {}};
  sim::RandomSweepOptions sweep;
  sweep.duration_s = 5;
  const sim::KeyframeMotion motion = sim::random_sweep_motion(7, c.subject.lower, c.subject.upper, sweep);
  sim::RecordingOptions recording;
  recording.frame_rate = 100;
  recording.frames = 400;
  c.recording = sim::simulate_recording(motion, c.subject, recording, 7);
  c.frames = evaluation::calibration_frame_indices({{0, 400}}, calibration::CalibrationOptions{});
  return c;
}

// The nominal: the true subject with the left foot's markers turned by a few degrees about the
// ankle (the origin of the frame they ride on), one left-thigh marker moved by 12 mm and the left
// thigh's bones 4 % longer.
body::BodyModel nominal_of(const body::BodyModel& truth, double foot_turn_rad) {
  body::BodyModel nominal = truth;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(foot_turn_rad, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  for (int m : body::markers_on_segment(truth, "LA"))
    nominal.markers[static_cast<std::size_t>(m)].offset =
        turn * truth.markers[static_cast<std::size_t>(m)].offset;
  nominal.markers[static_cast<std::size_t>(body::markers_on_segment(truth, "LH").front())].offset +=
      Eigen::Vector3d(8, -6, 6);
  for (body::Joint& joint : nominal.joints)
    if (body::segment_of_frame(truth, joint.parent_frame) == "LH") joint.translation *= 1.04;
  return nominal;
}

TEST(IdentifiableSubjectReference, ResetsTheGaugeToTheNominalAndKeepsTheRest) {
  const GaugeCase c =
      simulate_sweep(0);  // no soft tissue: the exact gauges are the only undetermined directions
  const body::BodyModel& truth = c.subject.model;
  const double turn = 3 * M_PI / 180;
  const body::BodyModel nominal = nominal_of(truth, turn);
  const evaluation::IdentifiableSubject identifiable = evaluation::identifiable_subject(
      nominal, c.subject, c.recording, c.frames, calibration::CalibrationOptions{}, kNoiseMm, kExactGauges);
  // The model's gauges (docs/calibration.md): 3 per ankle, 3 for the neck, 1 per wrist, with a gap
  // above them.
  EXPECT_LT(identifiable.information_ratios(10), 0.2 * identifiable.threshold);
  EXPECT_GT(identifiable.information_ratios(11), 2 * identifiable.threshold);
  EXPECT_EQ(identifiable.reset_directions, 11);
  EXPECT_EQ(identifiable.frames_used, static_cast<long>(c.frames.size()));
  ASSERT_EQ(identifiable.model.marker_count(), truth.marker_count());
  const std::vector<int> foot = body::markers_on_segment(truth, "LA");
  ASSERT_GE(foot.size(), 3u);
  for (int m = 0; m < truth.marker_count(); ++m) {
    const auto u = static_cast<std::size_t>(m);
    const bool on_foot = std::find(foot.begin(), foot.end(), m) != foot.end();
    // The foot's markers: the turn is a gauge, so the nominal's, up to the turn's second order
    // (the reset is linear: the part of a finite turn beyond its linearisation, 0.5 angle^2
    // |offset|, is not a gauge direction, and the projection of the linear part onto the
    // linearisation's gauges can differ by as much again; angle^2 |offset| is 0.4 mm at 3 degrees
    // for a marker 15 cm from the ankle). Every other marker: the true subject's.
    const Eigen::Vector3d expected = on_foot ? nominal.markers[u].offset : truth.markers[u].offset;
    const double tolerance = on_foot ? turn * turn * truth.markers[u].offset.norm() + 1e-3 : 1e-3;
    EXPECT_LT((identifiable.model.markers[u].offset - expected).norm(), tolerance)
        << truth.markers[u].name << (on_foot ? " (foot)" : "");
    if (on_foot) {  // and not the true subject's: the reset did happen
      const double turned = (nominal.markers[u].offset - truth.markers[u].offset).norm();
      EXPECT_GT(turned, 1.0);
      EXPECT_GT((identifiable.model.markers[u].offset - truth.markers[u].offset).norm(), 0.9 * turned);
    }
  }
  for (std::size_t j = 0; j < truth.joints.size(); ++j)
    EXPECT_LT((identifiable.model.joints[j].translation - truth.joints[j].translation).norm(), 1e-3)
        << truth.joints[j].name;
}

TEST(IdentifiableSubjectReference, WithoutAGaugeDifferenceIsTheTrueSubjectFit) {
  const GaugeCase c = simulate_sweep(8);  // with soft tissue
  const body::BodyModel& truth = c.subject.model;
  const body::BodyModel nominal = nominal_of(truth, 0);  // the thigh only
  const evaluation::IdentifiableSubject identifiable = evaluation::identifiable_subject(
      nominal, c.subject, c.recording, c.frames, calibration::CalibrationOptions{}, kNoiseMm, kExactGauges);
  EXPECT_GE(identifiable.reset_directions, 11);
  for (int m = 0; m < truth.marker_count(); ++m)
    EXPECT_LT((identifiable.model.markers[static_cast<std::size_t>(m)].offset -
               truth.markers[static_cast<std::size_t>(m)].offset)
                  .norm(),
              1e-3);
  sim::Subject reset = c.subject;
  reset.model = identifiable.model;
  const io::MotionTable reference = evaluation::true_subject_fit(c.subject, c.recording);
  const io::MotionTable fit = evaluation::true_subject_fit(reset, c.recording);
  ASSERT_EQ(fit.values.rows(), reference.values.rows());
  EXPECT_LT((fit.values - reference.values).cwiseAbs().maxCoeff(), 1e-4);
}

TEST(IdentifiableSubjectReference, ThresholdZeroKeepsTheTrueSubject) {
  const GaugeCase c = simulate_sweep(0);
  const body::BodyModel nominal = nominal_of(c.subject.model, 0.2);
  const evaluation::IdentifiableSubject identifiable = evaluation::identifiable_subject(
      nominal, c.subject, c.recording, c.frames, calibration::CalibrationOptions{}, kNoiseMm, 0);
  EXPECT_EQ(identifiable.reset_directions, 0);
  for (int m = 0; m < c.subject.model.marker_count(); ++m)
    EXPECT_EQ(identifiable.model.markers[static_cast<std::size_t>(m)].offset,
              c.subject.model.markers[static_cast<std::size_t>(m)].offset);
}

TEST(IdentifiableSubjectReference, RefusesAnotherModelOrBadFrames) {
  const GaugeCase c = simulate_sweep(0);
  body::BodyModel other = c.subject.model;
  other.markers.pop_back();
  EXPECT_THROW(
      evaluation::identifiable_subject(other, c.subject, c.recording, c.frames, {}, kNoiseMm, kExactGauges),
      std::invalid_argument);
  EXPECT_THROW(evaluation::identifiable_subject(c.subject.model, c.subject, c.recording, {400}, {}, kNoiseMm,
                                                kExactGauges),
               std::invalid_argument);
  EXPECT_THROW(
      evaluation::identifiable_subject(c.subject.model, c.subject, c.recording, c.frames, {}, 0, 1e-3),
      std::invalid_argument);
}

TEST(IdentifiableSubjectReference, CalibrationFramesFollowTheStretches) {
  calibration::CalibrationOptions options;
  options.skip_frames = 2;
  options.stride = 3;
  EXPECT_EQ(evaluation::calibration_frame_indices({{0, 10}, {100, 6}}, options),
            (std::vector<long>{2, 5, 8, 102, 105}));
}

}  // namespace
