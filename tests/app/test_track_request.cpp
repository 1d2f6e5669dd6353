#include <s2kf/app/track_request.hpp>
#include <s2kf/app/user_error.hpp>
#include <s2kf/track/tracker_options.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace {

using s2kf::app::OptionNames;
using s2kf::app::TrackRequest;
using s2kf::app::UserError;

// check_request's message for `request` spelled for `names`; empty when it passes.
std::string refusal(TrackRequest request, OptionNames names) {
  request.names = names;
  try {
    s2kf::app::check_request(request);
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

TEST(TrackRequest, TheDefaultsPass) {
  EXPECT_EQ(refusal(TrackRequest{}, OptionNames::program), "");
  EXPECT_EQ(refusal(TrackRequest{}, OptionNames::python), "");
}

TEST(TrackRequest, EachValueOutOfRangeIsNamedAsTheFrontEndSpellsIt) {
  struct Case {
    std::string option;  // as the program spells it, without the dashes
    std::function<void(TrackRequest&)> spoil;
  };
  const std::vector<Case> cases = {
      {"samples", [](TrackRequest& r) { r.samples = 2; }},
      {"samples", [](TrackRequest& r) { r.samples = 100002; }},
      {"calibration-samples", [](TrackRequest& r) { r.calibration_samples = 1; }},
      {"height", [](TrackRequest& r) { r.height_mm = 250; }},
      {"height", [](TrackRequest& r) { r.height_mm = std::nan(""); }},
      {"static-sd", [](TrackRequest& r) { r.static_sd_deg = 0.05; }},
      {"calibration-frames", [](TrackRequest& r) { r.calibration_frames = 9; }},
      {"calibration-shrink", [](TrackRequest& r) { r.calibration_shrink = -1; }},
      {"method", [](TrackRequest& r) { r.method = "ukf"; }},
      {"static-posture", [](TrackRequest& r) { r.static_posture = "loose"; }},
      {"static-refine", [](TrackRequest& r) { r.static_refine = true; }},
      {"static-alone", [](TrackRequest& r) { r.static_alone = true; }},
  };
  for (const Case& c : cases) {
    TrackRequest request;
    c.spoil(request);
    std::string python = c.option;
    std::replace(python.begin(), python.end(), '-', '_');
    EXPECT_NE(refusal(request, OptionNames::program).find("--" + c.option), std::string::npos) << c.option;
    const std::string in_python = refusal(request, OptionNames::python);
    EXPECT_NE(in_python.find(python), std::string::npos) << in_python;
    EXPECT_EQ(in_python.find("--"), std::string::npos) << in_python;
  }
}

TEST(TrackRequest, ContradictionsAreRefusedNamingBothSides) {
  TrackRequest both;
  both.markerset = "kit";
  both.subject = "subject.json";
  EXPECT_NE(refusal(both, OptionNames::program).find("give --markerset or --subject, not both"),
            std::string::npos);
  EXPECT_NE(refusal(both, OptionNames::python).find("give markerset or subject, not both"),
            std::string::npos);
  TrackRequest static_without_calibration;
  static_without_calibration.static_trial = "static.c3d";
  static_without_calibration.calibrate = false;
  EXPECT_NE(refusal(static_without_calibration, OptionNames::program).find("--no-calibrate"),
            std::string::npos);
  EXPECT_NE(refusal(static_without_calibration, OptionNames::python).find("calibrate=False"),
            std::string::npos);
  TrackRequest smoothed_baseline;
  smoothed_baseline.smooth = true;
  smoothed_baseline.method = "baseline";
  EXPECT_NE(refusal(smoothed_baseline, OptionNames::python).find("method='baseline'"), std::string::npos);
  TrackRequest alone_and_joint;
  alone_and_joint.static_trial = "static.c3d";
  alone_and_joint.static_alone = true;
  alone_and_joint.static_refine = true;
  EXPECT_NE(
      refusal(alone_and_joint, OptionNames::program).find("give --static-alone or --static-refine, not both"),
      std::string::npos);
  // The deprecated --static-refine says what replaced it, in the front end's words.
  TrackRequest deprecated;
  EXPECT_EQ(s2kf::app::deprecation_warning(deprecated), "");
  deprecated.static_trial = "static.c3d";
  deprecated.static_refine = true;
  EXPECT_EQ(refusal(deprecated, OptionNames::program), "");
  EXPECT_EQ(s2kf::app::deprecation_warning(deprecated),
            "--static-refine is deprecated: calibrating the static trial and the recording together is what "
            "--static does now (--static-alone calibrates on the static trial alone)");
  deprecated.names = OptionNames::python;
  EXPECT_NE(s2kf::app::deprecation_warning(deprecated).find("static_refine is deprecated"),
            std::string::npos);
  // Choices are listed; a removed gain says what replaced it.
  TrackRequest removed;
  removed.gain = "information-form-root-products";
  EXPECT_NE(refusal(removed, OptionNames::program).find("was removed"), std::string::npos);
  TrackRequest unknown;
  unknown.motion_model = "jerk";
  EXPECT_NE(refusal(unknown, OptionNames::program).find("random-walk"), std::string::npos);
}

TEST(TrackRequest, SessionOptionsCarryTheRequest) {
  TrackRequest request;
  request.samples = 51;
  request.motion_model = "constant-velocity";
  request.height_mm = 1750;
  request.calibration_frames = 400;
  request.calibration_threads = 1;
  request.uniform_noise = true;
  const s2kf::pipeline::SessionOptions options = s2kf::app::session_options(request, 120.0);
  EXPECT_EQ(options.tracker.samples, 51);
  EXPECT_EQ(options.tracker.motion_model, s2kf::track::motion_model_from_name("constant-velocity"));
  EXPECT_EQ(options.height_mm, 1750);
  EXPECT_EQ(options.calibration_frames, 400);
  EXPECT_EQ(options.calibration.threads, 1);
  EXPECT_FALSE(options.noise_from_calibration);
  EXPECT_TRUE(options.calibrate);
  // A subject file is calibrated already; a static trial is calibrated together with the recording
  // unless it is to be calibrated alone.
  request.subject = "subject.json";
  EXPECT_FALSE(s2kf::app::session_options(request, 120.0).calibrate);
  request.subject.clear();
  request.static_trial = "static.c3d";
  EXPECT_TRUE(s2kf::app::session_options(request, 120.0).calibrate);
  request.static_alone = true;
  EXPECT_FALSE(s2kf::app::session_options(request, 120.0).calibrate);
  request.static_alone = false;
  // The preset's noise follows the rate; the request's sample count replaces the preset's.
  request.preset = "paper";
  EXPECT_EQ(s2kf::app::tracker_options(request, 100.0).samples, 51);
  request.preset = "fast";
  EXPECT_THROW(s2kf::app::tracker_options(request, 100.0), UserError);
}

TEST(TrackRequest, TheNoBodyRemedyIsInTheFrontEndsWords) {
  TrackRequest request;
  EXPECT_EQ(s2kf::app::not_a_body_remedy(request),
            "give a marker set with --markerset, or track it anyway with --force");
  request.names = OptionNames::python;
  const std::string python = s2kf::app::not_a_body_remedy(request);
  EXPECT_EQ(python, "give a marker set with markerset=..., or track it anyway with force=True");
  EXPECT_EQ(python.find("--"), std::string::npos);
}

}  // namespace
