// The check of a calibrated subject: a plausible subject passes, and each kind of broken one (a
// bone-length factor outside the model's limits, a marker far from the marker set's placement, a
// marker or a whole fit the body cannot explain) is refused with a sentence naming it.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/calibration/calibration_check.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace {

using namespace s2kf;

struct Calibrated {
  body::BodyModel start;
  calibration::SubjectCalibration calibration;
};

/// The model's own marker set at 1750 mm, "calibrated" into a subject a few mm and per cent away.
Calibrated plausible() {
  Calibrated c;
  c.start =
      body::apply_marker_set(body::mmm_body_model(1750), body::model_marker_set(body::mmm_body_model(1000)));
  c.calibration.model = c.start;
  for (body::Marker& marker : c.calibration.model.markers) marker.offset += Eigen::Vector3d(5, -4, 3);
  c.calibration.segment_scale = {{"root", 1.03}, {"BLN", 0.97}, {"LK", 1.05}};
  c.calibration.marker_residual_rms_mm.assign(c.start.markers.size(), 6.0);
  calibration::CalibrationPass pass;
  pass.rms_before_mm = 14;
  pass.rms_after_mm = 7;
  c.calibration.passes.push_back(pass);
  return c;
}

bool mentions(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(CalibrationCheck, APlausibleSubjectPasses) {
  const Calibrated c = plausible();
  const calibration::CalibrationCheck check = calibration::check_calibration(c.start, c.calibration, false);
  EXPECT_TRUE(check.problem.empty()) << check.problem;
  EXPECT_EQ(check.worst_scale_segment, "LK");
  EXPECT_NEAR(check.worst_scale, 1.05, 1e-12);
  EXPECT_NEAR(check.worst_offset_shift_mm, std::sqrt(50.0), 1e-9);
  EXPECT_NEAR(check.rms_mm, 7, 1e-12);
}

// The real case: a negative bone length of the lower back in a static trial.
TEST(CalibrationCheck, AScaleOutsideTheLimitsNamesTheSegmentAndTheStance) {
  Calibrated c = plausible();
  c.calibration.segment_scale["BLN"] = -0.69;
  const std::string problem = calibration::check_calibration(c.start, c.calibration, true).problem;
  EXPECT_TRUE(mentions(problem, "segment BLN")) << problem;
  EXPECT_TRUE(mentions(problem, "-0.69")) << problem;
  EXPECT_TRUE(mentions(problem, "--static-pose")) << problem;
  EXPECT_EQ(problem.find('\n'), std::string::npos);
  // Too long is refused as well; a moving trial names no stance.
  c.calibration.segment_scale["BLN"] = 2.3;
  const std::string moving = calibration::check_calibration(c.start, c.calibration, false).problem;
  EXPECT_TRUE(mentions(moving, "segment BLN")) << moving;
  EXPECT_FALSE(mentions(moving, "--static-pose")) << moving;
}

// The real Plug-in Gait static trial alone: thighs 0.79 and 1.04. A static trial's sides must agree
// within 25 %; a moving recording's calibration is not judged so (its bending joints place them).
TEST(CalibrationCheck, AStaticTrialsTwoSidesMustBeAlike) {
  Calibrated c = plausible();
  c.calibration.segment_scale["LH"] = 0.79;
  c.calibration.segment_scale["RH"] = 1.04;
  const std::string problem = calibration::check_calibration(c.start, c.calibration, true).problem;
  EXPECT_TRUE(mentions(problem, "segments LH and RH came out 0.79 and 1.04")) << problem;
  EXPECT_TRUE(mentions(problem, "--static STATIC")) << problem;
  EXPECT_TRUE(calibration::check_calibration(c.start, c.calibration, false).problem.empty());
  c.calibration.segment_scale["LH"] = 0.95;  // 9 % apart: a person's
  EXPECT_TRUE(calibration::check_calibration(c.start, c.calibration, true).problem.empty());
}

TEST(CalibrationCheck, AMarkerFarFromItsPlaceIsNamedAsMislabelled) {
  Calibrated c = plausible();
  const int m = c.start.marker_index("RKNE") >= 0 ? c.start.marker_index("RKNE") : 7;
  const std::string name = c.start.markers[static_cast<std::size_t>(m)].name;
  c.calibration.model.markers[static_cast<std::size_t>(m)].offset += Eigen::Vector3d(0, 250, 0);
  const std::string problem = calibration::check_calibration(c.start, c.calibration, false).problem;
  EXPECT_TRUE(mentions(problem, "marker " + name)) << problem;
  EXPECT_TRUE(mentions(problem, "mislabelled")) << problem;
  EXPECT_TRUE(mentions(problem, "segment " + body::segment_of_frame(c.start, c.start.markers[m].frame)))
      << problem;
  // 199 mm is still a placement.
  c.calibration.model.markers[static_cast<std::size_t>(m)].offset =
      c.start.markers[static_cast<std::size_t>(m)].offset + Eigen::Vector3d(0, 199, 0);
  EXPECT_TRUE(calibration::check_calibration(c.start, c.calibration, false).problem.empty());
}

TEST(CalibrationCheck, ManyMarkersFarOffPointAtTheMarkerSet) {
  Calibrated c = plausible();
  for (body::Marker& marker : c.calibration.model.markers) marker.offset += Eigen::Vector3d(210, 0, 0);
  const std::string problem = calibration::check_calibration(c.start, c.calibration, false).problem;
  EXPECT_TRUE(mentions(problem, "marker set that is not the recording's")) << problem;
}

TEST(CalibrationCheck, AMarkerOrAFitTheBodyCannotExplainIsRefused) {
  Calibrated c = plausible();
  c.calibration.marker_residual_rms_mm[3] = 45;
  const std::string marker = calibration::check_calibration(c.start, c.calibration, false).problem;
  EXPECT_TRUE(mentions(marker, "marker " + c.start.markers[3].name)) << marker;
  c = plausible();
  c.calibration.passes.front().rms_after_mm = std::nan("");
  EXPECT_TRUE(
      mentions(calibration::check_calibration(c.start, c.calibration, false).problem, "RMS marker distance"));
  c.calibration.passes.front().rms_after_mm = 61;
  EXPECT_TRUE(mentions(calibration::check_calibration(c.start, c.calibration, false).problem, "61.0 mm"));
}

}  // namespace
