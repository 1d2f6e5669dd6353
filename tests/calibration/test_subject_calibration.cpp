// Subject calibration: on synthetic recordings of a subject who differs from the model (placement
// offsets, bone lengths), the calibration must move the model towards the true subject.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/marker_set_mapping.hpp>
#include <s2kf/calibration/height_estimate.hpp>
#include <s2kf/calibration/subject_calibration.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/sim/random_sweep.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>
#include <s2kf/track/tracking_run.hpp>

#include "sweep_recording.hpp"
#include "tracker_samples.hpp"

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include "address_sanitizer.hpp"

namespace {

using namespace s2kf;

struct Synthetic {
  sim::Subject subject;
  sim::Recording recording;
  std::vector<Eigen::Matrix3Xd> points;
  std::vector<Eigen::Array<bool, Eigen::Dynamic, 1>> visible;
};

Synthetic make_synthetic(Eigen::Index frames, double soft_tissue_mm, std::uint64_t seed,
                         double height_mm = 1750) {
  Synthetic s;
  sim::SubjectOptions subject_options;  // defaults: placement 8 mm, segment scale 3 %
  subject_options.soft_tissue_mm = soft_tissue_mm;
  subject_options.height_mm = height_mm;
  s.subject = sim::make_subject(body::mmm_body_model(1750), subject_options, seed);
  s.recording =
      test_support::sweep_recording(s.subject, seed, frames, static_cast<double>(frames) / 100.0 + 1.0);
  for (Eigen::Index k = 0; k < frames; ++k) {
    s.points.push_back(s.recording.frame(k));
    s.visible.push_back(s.recording.visible.col(k));
  }
  return s;
}

/// Mean 3-D distance (mm) between the calibrated marker offsets and the subject's true ones, after
/// undoing on the end segments what no recording can tell apart: a foot's markers turned about
/// its ankle (3 joints: a constant offset of the ankle angles turns the foot back), a hand's turned
/// about the wrist's last axis (y), and the head's moved rigidly (3 neck joints, and no marker
/// between the two neck joint groups, so the upper neck's length is unobservable too). Every other
/// segment is compared as it is.
double offset_error(const body::BodyModel& model, const sim::Subject& subject, bool undo_gauge = true) {
  double sum = 0;
  int count = 0;
  std::vector<std::string> segments;
  for (const body::Marker& marker : model.markers) {
    const std::string segment = body::segment_of_frame(model, marker.frame);
    if (std::find(segments.begin(), segments.end(), segment) == segments.end()) segments.push_back(segment);
  }
  for (const std::string& segment : segments) {
    const std::vector<int> markers = body::markers_on_segment(model, segment);
    Eigen::Matrix3Xd estimate(3, static_cast<Eigen::Index>(markers.size())), truth = estimate;
    for (std::size_t k = 0; k < markers.size(); ++k) {
      estimate.col(static_cast<Eigen::Index>(k)) = model.markers[static_cast<std::size_t>(markers[k])].offset;
      truth.col(static_cast<Eigen::Index>(k)) =
          subject.model.markers[static_cast<std::size_t>(markers[k])].offset;
    }
    if (undo_gauge && (segment == "LA" || segment == "RA")) {
      // Rotation about the frame origin (Kabsch without translation).
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(truth * estimate.transpose(),
                                                  Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
      d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
      estimate = svd.matrixU() * d * svd.matrixV().transpose() * estimate;
    } else if (undo_gauge && (segment == "LW" || segment == "RW")) {
      // Rotation about y: the angle that best turns the x-z components onto the truth's.
      double sine = 0, cosine = 0;
      for (Eigen::Index k = 0; k < estimate.cols(); ++k) {
        // R_y(a) maps (x, z) to (x cos a + z sin a, -x sin a + z cos a).
        const double x = estimate(0, k), z = estimate(2, k), tx = truth(0, k), tz = truth(2, k);
        cosine += x * tx + z * tz;
        sine += z * tx - x * tz;
      }
      estimate =
          Eigen::AngleAxisd(std::atan2(sine, cosine), Eigen::Vector3d::UnitY()).toRotationMatrix() * estimate;
    } else if (undo_gauge && segment == "BUN") {
      estimate =
          Eigen::umeyama(estimate, truth, false).topLeftCorner<3, 4>() * estimate.colwise().homogeneous();
    }
    for (Eigen::Index k = 0; k < estimate.cols(); ++k) sum += (estimate.col(k) - truth.col(k)).norm();
    count += static_cast<int>(estimate.cols());
  }
  return sum / count;
}

/// Largest relative error of the calibrated segment length factors against the subject's, over
/// the segments that carry markers. The lumbar (BP) and upper-neck (BLN) segments carry none in any
/// marker set: their lengths are seen only through joint centres, and the upper neck's not at all
/// (it trades freely against the head markers' offsets). `height_ratio` is the subject's height
/// over the model's; `start` replaces the calibrated factors (for the error before calibration).
double worst_scale_error(const calibration::SubjectCalibration& calibration, const sim::Subject& subject,
                         double height_ratio, const std::map<std::string, double>& start = {}) {
  double worst = 0;
  for (const auto& [segment, factor] : calibration.segment_scale) {
    if (segment == "BLN" || segment == "BP") continue;
    const auto found = std::find(subject.segments.begin(), subject.segments.end(), segment);
    const double truth = height_ratio * subject.segment_scale(found - subject.segments.begin());
    const double estimate = start.empty() ? factor : start.at(segment);
    worst = std::max(worst, std::abs(estimate / truth - 1));
  }
  return worst;
}

track::TrackerOptions fast_options() {
  track::TrackerOptions options;
  options.samples = 101;  // keeps the test fast; the default 301 gives the same picture
  return options;
}

/// Calibrates `model` on the synthetic recording with the default options (or the given
/// weak-direction shrinkage) and no final tracking pass (the tests compare against the truth
/// instead).
calibration::SubjectCalibration calibrate(const body::BodyModel& model, const Synthetic& s,
                                          std::optional<double> shrink = std::nullopt) {
  calibration::CalibrationOptions options;
  options.final_pass = false;
  if (shrink) options.weak_direction_shrink = *shrink;
  return calibration::calibrate_subject(model, body::map_markers(s.recording.labels, model.marker_names()),
                                        fast_options(), s.recording, test::tracker_samples(fast_options()),
                                        options);
}

io::MotionTable track_all(const body::BodyModel& model, const Synthetic& s,
                          const track::TrackerOptions& options) {
  const body::MarkerMapping mapping = body::map_markers(s.recording.labels, model.marker_names());
  track::Tracker tracker(model, mapping, options, 100.0, test::tracker_samples(options));
  std::size_t next = 0;
  auto frames = [&](MarkerFrame& frame) {
    if (next >= s.points.size()) return false;
    frame.index = static_cast<std::int64_t>(next);
    frame.positions = s.points[next];
    frame.visible = s.visible[next];
    ++next;
    return true;
  };
  return track::run_tracking(tracker, frames, 100.0, model.joint_names()).motion;
}

io::MotionTable truth_table(const Synthetic& s, const body::BodyModel& model) {
  io::MotionTable truth;
  truth.joint_names = model.joint_names();
  truth.values.resize(s.recording.frames(), 6 + model.joint_count());
  for (Eigen::Index k = 0; k < s.recording.frames(); ++k) {
    const body::Pose& pose = s.recording.truth[static_cast<std::size_t>(k)];
    truth.values.row(k).head<3>() = pose.root_position.transpose();
    truth.values.row(k).segment<3>(3) = pose.root_rpy.transpose();
    truth.values.row(k).tail(model.joint_count()) = pose.joints.transpose();
    truth.frame.push_back(k);
    truth.time.push_back(s.recording.time_s(k));
  }
  return truth;
}

TEST(SubjectCalibration, RecoversOffsetsAndBoneLengthsOfTheTrueSubject) {
  S2KF_SKIP_UNDER_SANITIZERS();
  // A 1830 mm subject without soft tissue: marker placement (8 mm SD per coordinate) and segment
  // lengths (3 % SD) that the bundle adjustment can recover down to the sensor noise (0.7 mm). The
  // model is scaled to the height estimated from the markers, as s2kf track does.
  const double height = 1830;
  const Synthetic s = make_synthetic(400, 0.0, 7, height);
  const body::BodyModel base = body::mmm_body_model(1750);
  const body::MarkerMapping mapping = body::map_markers(s.recording.labels, base.marker_names());
  calibration::HeightEstimator estimator(base, mapping);
  for (std::size_t k = 0; k < s.points.size(); ++k) estimator.add_frame(s.points[k], s.visible[k]);
  ASSERT_TRUE(estimator.height_mm().has_value());
  const body::BodyModel model = base.scaled(*estimator.height_mm());
  const double ratio = height / model.height_mm;
  struct Recovery {
    double offsets_mm, lengths, residual_mm;
  };
  const auto recovered = [&](const calibration::SubjectCalibration& calibration, const char* name) {
    const Recovery r{offset_error(calibration.model, s.subject),
                     worst_scale_error(calibration, s.subject, ratio),
                     calibration.passes.back().rms_after_mm};
    std::cout << name << ": offset error " << r.offsets_mm << " mm, worst segment length error "
              << 100 * r.lengths << " %, RMS marker residual " << r.residual_mm << " mm\n";
    // Joint limits are the model's: the calibration changes lengths and offsets only.
    for (int j = 0; j < model.joint_count(); ++j) {
      EXPECT_EQ(calibration.model.joints[static_cast<std::size_t>(j)].lower,
                model.joints[static_cast<std::size_t>(j)].lower);
      EXPECT_EQ(calibration.model.joints[static_cast<std::size_t>(j)].upper,
                model.joints[static_cast<std::size_t>(j)].upper);
    }
    return r;
  };
  const calibration::SubjectCalibration exact = calibrate(model, s, 0.0);
  std::map<std::string, double> ones;
  for (const auto& entry : exact.segment_scale) ones[entry.first] = 1.0;
  const double before = offset_error(model, s.subject),
               scales_before = worst_scale_error(exact, s.subject, ratio, ones);
  std::cout << "height " << height << " mm, estimated " << model.height_mm
            << " mm; nominal subject: offset error " << before << " mm, worst segment length error "
            << 100 * scales_before << " %\n";
  EXPECT_GT(before, 10.0);         // the subject really differs from the model
  EXPECT_GT(scales_before, 0.02);  // ... and its segments too
  // Without the shrinkage every direction the data see is estimated: the targets, offsets
  // within 5 mm and segment lengths within 1 %, down to the sensor noise (0.7 mm per coordinate is
  // 1.2 mm in 3-D).
  const Recovery unshrunk = recovered(exact, "no shrinkage");
  EXPECT_LT(unshrunk.offsets_mm, 5.0);
  EXPECT_LT(unshrunk.lengths, 0.01);
  EXPECT_LT(unshrunk.residual_mm, 2.0);
  // The default shrinkage (c = 0.03) pulls the weakly seen offset directions a little towards the
  // marker set. That is what makes realistic subjects, whose soft tissue would otherwise decide
  // those directions, track better; on this subject without soft tissue it costs some exactness
  // (measured: offsets 1.5 -> 2.6 mm, lengths 0.9 -> 1.4 %), bounded here.
  const Recovery shrunk = recovered(calibrate(model, s), "default shrinkage");
  EXPECT_LT(shrunk.offsets_mm, 5.0);
  EXPECT_LT(shrunk.lengths, 0.015);
  EXPECT_LT(shrunk.residual_mm, 2.0);
  EXPECT_GT(shrunk.offsets_mm, unshrunk.offsets_mm);  // the shrinkage is on by default
}

// The bundle adjustment alone, started at the true poses of a subject without soft tissue: it
// recovers the subject as the whole calibration does, and its per-marker residuals name the one
// marker that carries extra noise.
TEST(SubjectCalibration, AdjustsTheSubjectAtGivenPoses) {
  S2KF_SKIP_UNDER_SANITIZERS();
  Synthetic s = make_synthetic(200, 0.0, 7);
  // Marker 10 jitters by 6 mm SD per coordinate on top of the 0.7 mm sensor noise.
  std::mt19937_64 random(3);
  std::normal_distribution<double> jitter(0.0, 6.0);
  for (Eigen::Index k = 0; k < s.recording.frames(); ++k)
    for (int i = 0; i < 3; ++i) s.recording.positions(30 + i, k) += jitter(random);
  const body::BodyModel model = body::mmm_body_model(1750);
  const body::MarkerMapping mapping = body::map_markers(s.recording.labels, model.marker_names());
  std::vector<std::pair<long, body::Pose>> poses;
  for (long k = 0; k < s.recording.frames(); k += 2)
    poses.emplace_back(k, s.recording.truth[static_cast<std::size_t>(k)]);
  calibration::CalibrationOptions options;
  options.weak_direction_shrink = 0;
  const calibration::SubjectCalibration adjusted =
      calibration::adjust_subject_at_poses(model, mapping, fast_options(), s.recording, poses, options);
  ASSERT_EQ(adjusted.passes.size(), 1u);
  EXPECT_EQ(adjusted.passes[0].frames_used, 100);
  EXPECT_GT(offset_error(model, s.subject), 10.0);
  EXPECT_LT(offset_error(adjusted.model, s.subject), 5.0);
  EXPECT_LT(worst_scale_error(adjusted, s.subject, 1.0), 0.015);
  EXPECT_GT(adjusted.passes[0].rms_before_mm, 10.0);
  EXPECT_LT(adjusted.passes[0].rms_after_mm, 3.0);
  const std::vector<double>& residual = adjusted.marker_residual_rms_mm;
  ASSERT_EQ(residual.size(), static_cast<std::size_t>(model.marker_count()));
  const auto largest = std::max_element(residual.begin(), residual.end());
  EXPECT_EQ(largest - residual.begin(), 10);
  EXPECT_GT(*largest, 6.0);  // sqrt(3) x 6 mm = 10.4, less what the offset and poses absorb (7.9)
  for (std::size_t m = 0; m < residual.size(); ++m)
    if (m != 10) {
      EXPECT_LT(residual[m], 3.0) << model.markers[m].name;
    }

  // Poses it cannot use are refused with a sentence.
  std::vector<std::pair<long, body::Pose>> outside{{s.recording.frames(), s.recording.truth.front()}};
  EXPECT_THROW(
      calibration::adjust_subject_at_poses(model, mapping, fast_options(), s.recording, outside, options),
      std::invalid_argument);
  std::vector<std::pair<long, body::Pose>> short_pose{{0, s.recording.truth.front()}};
  short_pose[0].second.joints.resize(3);
  EXPECT_THROW(
      calibration::adjust_subject_at_poses(model, mapping, fast_options(), s.recording, short_pose, options),
      std::invalid_argument);
  EXPECT_THROW(calibration::adjust_subject_at_poses(model, mapping, fast_options(), s.recording, {}, options),
               std::invalid_argument);
  // So are per-marker options of another length (they are read by marker index).
  calibration::CalibrationOptions short_weights = options;
  short_weights.marker_weight.assign(3, 1.0);
  EXPECT_THROW(
      calibration::adjust_subject_at_poses(model, mapping, fast_options(), s.recording, poses, short_weights),
      std::invalid_argument);
  calibration::CalibrationOptions short_flags = options;
  short_flags.placed_by_motion.assign(3, true);
  EXPECT_THROW(
      calibration::adjust_subject_at_poses(model, mapping, fast_options(), s.recording, poses, short_flags),
      std::invalid_argument);
}

// A subject whose markers are only misplaced: no soft tissue and the model's bone lengths (a static
// pose cannot tell them from the offsets of the markers beyond each joint).
sim::Subject placement_only_subject(std::uint64_t seed) {
  sim::SubjectOptions options;
  options.soft_tissue_mm = 0;
  options.segment_scale_sd = 0;
  return sim::make_subject(body::mmm_body_model(1750), options, seed);
}

// Three seconds standing still in the model's zero pose, the root 530 mm up (a static trial).
sim::KeyframeMotion standing_still(int joint_count) {
  sim::KeyframeMotion still;
  still.name = "static";
  still.times = {0.0, 3.0};
  still.root_positions = Eigen::Matrix3Xd::Zero(3, 2);
  still.root_positions.row(2).setConstant(530);
  still.root_rpy = Eigen::Matrix3Xd::Zero(3, 2);
  still.joints = Eigen::MatrixXd::Zero(joint_count, 2);
  return still;
}

// The static trial of `still` on `subject`: 300 frames (3 s at 100 Hz).
sim::Recording static_recording(const sim::KeyframeMotion& still, const sim::Subject& subject,
                                unsigned seed) {
  sim::RecordingOptions options;
  options.frames = 300;
  return sim::simulate_recording(still, subject, options, seed);
}

// A static trial in the model's zero pose fixes the gauges, the markers' placement about the joints
// that no recording tells from a constant offset of the joint angles (a foot's markers turned about
// its ankle, a hand's about the wrist): with the posture's prior (static_pose_sd_rad) the offsets
// come out near where they were placed, gauges included; without it the bundle adjustment leaves
// those directions to the marker set's values. Placement errors only (no soft tissue, the model's
// bone lengths, kept: a static pose cannot tell them from the offsets of the markers beyond each
// joint).
TEST(SubjectCalibration, AStaticTrialFixesTheGauges) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const sim::Subject subject = placement_only_subject(7);
  const sim::KeyframeMotion still = standing_still(subject.model.joint_count());
  const sim::Recording recording = static_recording(still, subject, 7);
  const body::BodyModel model = body::mmm_body_model(1750);
  const body::MarkerMapping mapping = body::map_markers(recording.labels, model.marker_names());
  calibration::CalibrationOptions options;
  options.final_pass = false;
  options.weak_direction_shrink = 0;
  options.estimate_segment_scales = false;  // a static pose cannot tell them from the offsets
  const auto calibrated = [&](double sd_rad) {
    calibration::CalibrationOptions o = options;
    o.static_pose_sd_rad = sd_rad;
    return calibration::calibrate_subject(model, mapping, fast_options(), recording,
                                          test::tracker_samples(fast_options()), o)
        .model;
  };
  const double before = offset_error(model, subject, false);
  const double free = offset_error(calibrated(0.0), subject, false);
  const body::BodyModel posed_model = calibrated(3.0 * kPi / 180.0);
  const double posed = offset_error(posed_model, subject, false);
  std::cout << "offset error, gauges included: marker set " << before
            << " mm, static trial without the posture " << free << " mm, with it " << posed << " mm\n";
  // Measured: 13.7 mm as placed, 6.5 without the posture, 2.4 with it (what remains is the whole
  // body's markers moved rigidly against the root's pose, which only the offsets' prior decides).
  EXPECT_GT(before, 10.0);
  EXPECT_LT(posed, 3.0);
  EXPECT_GT(free, 2.0 * posed);
  options.static_pose_sd_rad = -1;
  EXPECT_THROW(options.validate(), std::invalid_argument);
}

// A marker set whose markers all lean together (every offset turned 3 degrees about the forward
// axis through the root, as a template fit of clusters can place them): a static trial shows the
// same markers on an upright subject or on a leaning one with the set's offsets, since the posture
// prior holds only the joint angles. With the upright prior (static_upright_sd_rad) the root stays
// upright and the offsets come out near the subject's; without it they keep the lean. Placement
// errors only; the posture held exactly, as for markers placed by their motion.
TEST(SubjectCalibration, TheUprightPriorKeepsALeaningMarkerSetOffTheStaticTrial) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const sim::Subject subject = placement_only_subject(3);
  const sim::KeyframeMotion still = standing_still(subject.model.joint_count());
  const sim::Recording recording = static_recording(still, subject, 3);
  body::BodyModel leaning = subject.model;
  const body::FrameTransforms zero =
      body::joint_frames(leaning, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(),
                         Eigen::VectorXd::Zero(leaning.joint_count()));
  const Eigen::Matrix3d lean =
      Eigen::AngleAxisd(3.0 * kPi / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (body::Marker& marker : leaning.markers) {
    const auto f = static_cast<std::size_t>(marker.frame);
    const Eigen::Vector3d at = zero.origins[f] + zero.rotations[f] * marker.offset;
    marker.offset = zero.rotations[f].transpose() * (lean * at - zero.origins[f]);
  }
  const body::MarkerMapping mapping = body::map_markers(recording.labels, leaning.marker_names());
  const auto calibrated = [&](double upright_sd_deg) {
    calibration::CalibrationOptions options;
    options.final_pass = false;
    options.estimate_segment_scales = false;
    options.static_pose_sd_rad = 0.5 * kPi / 180.0;
    options.static_upright_sd_rad = upright_sd_deg * kPi / 180.0;
    return offset_error(calibration::calibrate_subject(leaning, mapping, fast_options(), recording,
                                                       test::tracker_samples(fast_options()), options)
                            .model,
                        subject, false);
  };
  const double before = offset_error(leaning, subject, false);
  const double free = calibrated(0.0), upright = calibrated(0.5);
  std::cout << "offset error, gauges included: leaning marker set " << before << " mm, static trial " << free
            << " mm with its tilt free, " << upright << " mm held upright\n";
  // Measured: 24.8 mm as leaning, 24.8 with the tilt free, 11.5 held upright (the rest is the
  // markers' own misplacement, 8 mm per coordinate, and the weak-direction shrinkage).
  EXPECT_GT(free, 0.7 * before);
  EXPECT_LT(upright, 0.6 * free);
  calibration::CalibrationOptions bad;
  bad.static_upright_sd_rad = -1;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// The lab's vertical for the upright prior: the coordinate axis, with its sign, nearest the roots'
// vertical axes; a y-up lab gives +y, a subject leaning 20 degrees still its lab's axis.
TEST(SubjectCalibration, TheLabsVerticalIsTheAxisNearestTheRootsVertical) {
  const Eigen::Matrix3d y_up = Eigen::AngleAxisd(-kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d leaning = Eigen::AngleAxisd(20.0 * kPi / 180.0, Eigen::Vector3d::UnitZ()) * y_up *
                                  Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY());
  EXPECT_EQ(calibration::nearest_lab_vertical({y_up, leaning}), Eigen::Vector3d(0, 1, 0));
  const Eigen::Matrix3d upside_down = Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_EQ(calibration::nearest_lab_vertical({upside_down}), Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(calibration::nearest_lab_vertical({}), Eigen::Vector3d::Zero());
}

// People do not stand in the reference pose: a static trial held with every joint a few degrees
// off it (SD 3 degrees, what the posture's prior says), calibrated with the default options. With
// the posture estimated (`near`) the posture comes out nearer the one held than the reference is,
// and the offsets near where they were placed, gauges included; holding every frame to the
// reference (`exact`) puts the stance into the markers' placement instead. A `near` that held the
// posture at the reference, or left every gauge to the marker set, fails these checks.
TEST(SubjectCalibration, AStaticTrialOffTheReferencePoseIsEstimated) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const sim::Subject subject = placement_only_subject(11);
  const double sd_rad = 3.0 * kPi / 180.0;
  sim::KeyframeMotion still = standing_still(subject.model.joint_count());
  std::mt19937_64 draw(11);
  std::normal_distribution<double> off(0.0, sd_rad);
  for (int j = 0; j < subject.model.joint_count(); ++j) {
    const body::Joint& joint = subject.model.joints[static_cast<std::size_t>(j)];
    still.joints.row(j).setConstant(std::clamp(off(draw), joint.lower + 0.01, joint.upper - 0.01));
  }
  const sim::Recording recording = static_recording(still, subject, 11);
  const body::BodyModel model = body::mmm_body_model(1750);
  const body::MarkerMapping mapping = body::map_markers(recording.labels, model.marker_names());
  const Eigen::VectorXd held = still.joints.col(0);
  const auto calibrated = [&](bool estimated, double& posture_rms_deg) {
    calibration::CalibrationOptions options;  // the default shrinkage, as s2kf's static calibration
    options.final_pass = false;
    options.estimate_segment_scales = false;
    options.static_pose_sd_rad = sd_rad;
    options.static_posture_estimated = estimated;
    const calibration::SubjectCalibration result = calibration::calibrate_subject(
        model, mapping, fast_options(), recording, test::tracker_samples(fast_options()), options);
    posture_rms_deg =
        std::sqrt((result.static_posture - held).squaredNorm() / static_cast<double>(held.size())) * 180 /
        kPi;
    return offset_error(result.model, subject, false);
  };
  double near_posture = 0, exact_posture = 0;
  const double before = offset_error(model, subject, false);
  const double near = calibrated(true, near_posture);
  const double exact = calibrated(false, exact_posture);
  const double stance_rms_deg = std::sqrt(held.squaredNorm() / static_cast<double>(held.size())) * 180 / kPi;
  std::cout << "stance " << stance_rms_deg
            << " deg RMS off the reference; offset error, gauges included: marker set " << before
            << " mm, near " << near << " mm, exact " << exact << " mm; posture off the one held: near "
            << near_posture << " deg RMS, exact " << exact_posture << " deg RMS\n";
  // Measured: stance 2.4 degrees RMS; offsets 10.8 mm as placed, near 4.0, exact 9.6; posture
  // 1.6 degrees RMS off the one held near, 2.0 exact.
  EXPECT_GT(before, 10.0);
  EXPECT_LT(near, 0.5 * before);
  EXPECT_LT(near, 0.6 * exact);
  EXPECT_LT(near_posture, 0.8 * stance_rms_deg);
  EXPECT_LT(near_posture, exact_posture);
}

// With the elbow straight, the upper arm's roll about its long axis (RSz) and the forearm's (REz)
// turn about one line: a static trial sees only their sum, and its posture's prior splits it
// evenly, the upper arm's markers' placement taking the rest. A stance with the upper arm rolled
// +6 degrees and the forearm -6 (their sum 0) comes out far from it from the static trial alone. Calibrated
// together with a moving trial of the same subject in which the elbow bends
// (CalibrationOptions::static_frames), the hinge shows the upper arm's roll, and the posture
// estimated for the static trial comes out near the one held. Placement errors only (no soft
// tissue, the model's bone lengths).
TEST(SubjectCalibration, AMovingTrialBesideTheStaticOneSplitsTheArmsRoll) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const sim::Subject subject = placement_only_subject(5);
  const body::BodyModel model = body::mmm_body_model(1750);
  const auto joint = [&](const std::string& name) {
    const std::vector<std::string> names = model.joint_names();
    return static_cast<Eigen::Index>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  const Eigen::Index shoulder_roll = joint("RSz"), forearm_roll = joint("REz");
  const double held_rad = 6.0 * kPi / 180.0;
  sim::KeyframeMotion still = standing_still(subject.model.joint_count());
  still.joints.row(shoulder_roll).setConstant(held_rad);
  still.joints.row(forearm_roll).setConstant(-held_rad);
  const sim::Recording static_trial = static_recording(still, subject, 5);
  const sim::Recording moving = test_support::sweep_recording(subject, 5, 400, 5.0);
  MarkerSequence both = static_trial;  // the static trial first, then the moving trial
  both.positions.conservativeResize(Eigen::NoChange, static_trial.frame_count() + moving.frame_count());
  both.positions.rightCols(moving.frame_count()) = moving.positions;
  both.visible.conservativeResize(Eigen::NoChange, both.positions.cols());
  both.visible.rightCols(moving.frame_count()) = moving.visible;
  const body::MarkerMapping mapping = body::map_markers(static_trial.labels, model.marker_names());
  calibration::CalibrationOptions options;  // the default shrinkage
  options.final_pass = false;
  options.estimate_segment_scales = false;
  options.static_pose_sd_rad = 3.0 * kPi / 180.0;
  options.static_posture_estimated = true;
  const calibration::SubjectCalibration alone = calibration::calibrate_subject(
      model, mapping, fast_options(), static_trial, test::tracker_samples(fast_options()), options);
  options.static_frames = static_trial.frame_count();
  options.restart_frames = {static_cast<long>(static_trial.frame_count())};
  const calibration::SubjectCalibration joint_calibration = calibration::calibrate_subject(
      model, mapping, fast_options(), both, test::tracker_samples(fast_options()), options);
  const auto degrees = [](double rad) { return rad * 180.0 / kPi; };
  const double alone_error = degrees(alone.static_posture(shoulder_roll) - held_rad);
  const double joint_error = degrees(joint_calibration.static_posture(shoulder_roll) - held_rad);
  std::cout << "upper arm's roll held +6 deg, forearm's -6: estimated off by " << alone_error
            << " deg from the static trial alone, " << joint_error << " deg with the moving trial; forearm "
            << degrees(alone.static_posture(forearm_roll) + held_rad) << " and "
            << degrees(joint_calibration.static_posture(forearm_roll) + held_rad) << " deg\n";
  // Measured: the upper arm's roll 7.5 degrees off from the static trial alone, 2.7 with the moving
  // trial; the forearm's 4.5 and 2.1.
  EXPECT_GT(std::abs(alone_error), 4.0);
  EXPECT_LT(std::abs(joint_error), 0.5 * std::abs(alone_error));
  EXPECT_LT(std::abs(joint_error), 3.5);
  // The static frames' posture is the static trial's alone: the moving frames get no prior.
  EXPECT_GT(joint_calibration.passes.front().frames_used, alone.passes.front().frames_used + 50);
  options.static_frames = -1;
  EXPECT_THROW(options.validate(), std::invalid_argument);
}

// A static trial calibrated with a moving one counts as the distinct postures it shows
// (CalibrationOptions::static_distinct_mm): its frames weigh their number over the trial's, data and
// priors alike. Every static pose given twice then gives the subject of each given once (the
// repeats show no new posture: every weight, the posture's shared prior and the shrinkage measured
// against the static trial come out as before); counted frame by frame (0), the static trial
// weighs twice and the subject moves. Soft tissue (8 mm) makes the two trials disagree, so the
// static trial's weight matters.
TEST(SubjectCalibration, AStaticTrialCountsAsTheDistinctPosturesItShows) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const sim::Subject subject = sim::make_subject(body::mmm_body_model(1750), sim::SubjectOptions{}, 9);
  const sim::Recording static_trial =
      static_recording(standing_still(subject.model.joint_count()), subject, 9);
  const sim::Recording moving = test_support::sweep_recording(subject, 9, 200, 3.0);
  MarkerSequence both = static_trial;
  both.append_frames(moving);
  const body::BodyModel model = body::mmm_body_model(1750);
  const body::MarkerMapping mapping = body::map_markers(static_trial.labels, model.marker_names());
  std::vector<std::pair<long, body::Pose>> once, twice, moving_poses;
  for (long k = 0; k < static_trial.frame_count(); k += 10) {
    once.emplace_back(k, static_trial.truth[static_cast<std::size_t>(k)]);
    twice.insert(twice.end(), 2, once.back());
  }
  for (long k = 0; k < moving.frame_count(); k += 4)
    moving_poses.emplace_back(static_trial.frame_count() + k, moving.truth[static_cast<std::size_t>(k)]);
  once.insert(once.end(), moving_poses.begin(), moving_poses.end());
  twice.insert(twice.end(), moving_poses.begin(), moving_poses.end());
  calibration::CalibrationOptions options;  // the default shrinkage
  options.static_pose_sd_rad = 3.0 * kPi / 180.0;
  options.static_posture_estimated = true;
  options.static_frames = static_trial.frame_count();
  options.static_distinct_mm = 3.0;  // the drift moves the markers by less between some of the poses
  const auto adjusted = [&](const std::vector<std::pair<long, body::Pose>>& poses, double distinct_mm) {
    calibration::CalibrationOptions o = options;
    o.static_distinct_mm = distinct_mm;
    return calibration::adjust_subject_at_poses(model, mapping, fast_options(), both, poses, o);
  };
  const calibration::SubjectCalibration reference = adjusted(once, options.static_distinct_mm);
  const calibration::SubjectCalibration repeated = adjusted(twice, options.static_distinct_mm);
  const auto largest_shift = [&](const calibration::SubjectCalibration& a) {
    double shift = 0;
    for (std::size_t m = 0; m < model.markers.size(); ++m)
      shift = std::max(shift, (a.model.markers[m].offset - reference.model.markers[m].offset).norm());
    return shift;
  };
  EXPECT_LT(largest_shift(repeated), 1e-3);
  for (const auto& [segment, scale] : reference.segment_scale)
    EXPECT_NEAR(repeated.segment_scale.at(segment), scale, 1e-6) << segment;
  EXPECT_LT((repeated.static_posture - reference.static_posture).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_GT(largest_shift(adjusted(twice, 0)), 0.1);
  // The still trial's 30 poses show fewer distinct ones: counted frame by frame, the subject differs.
  EXPECT_GT(largest_shift(adjusted(once, 0)), 0.1);
  options.static_distinct_mm = -1;
  EXPECT_THROW(options.validate(), std::invalid_argument);
}

// Markers placed by their motion (CalibrationOptions::placed_by_motion) start where the template fit
// put them, which knows nothing of their turn about the joint: the feet's markers here are turned
// 10 degrees about each ankle. Only the static trial's posture shows that turn, and a still static
// trial counts as one posture beside the moving trial (static_distinct_mm), so the offsets' prior
// and the weak-direction shrinkage towards the set would keep half of it; flagged as placed, the
// static trial decides it. Placement errors only, poses given (adjust_subject_at_poses).
TEST(SubjectCalibration, AStaticTrialDecidesTheTurnOfMarkersPlacedByTheirMotion) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const sim::Subject subject = placement_only_subject(13);
  const sim::Recording static_trial =
      static_recording(standing_still(subject.model.joint_count()), subject, 13);
  const sim::Recording moving = test_support::sweep_recording(subject, 13, 200, 3.0);
  MarkerSequence both = static_trial;
  both.append_frames(moving);
  body::BodyModel model = subject.model;  // the true placement, the feet's markers turned
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(10.0 * kPi / 180.0, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  std::vector<bool> placed(model.markers.size(), false);
  for (const std::string segment : {"LA", "RA"})
    for (const int m : body::markers_on_segment(model, segment)) {
      model.markers[static_cast<std::size_t>(m)].offset =
          turn * model.markers[static_cast<std::size_t>(m)].offset;
      placed[static_cast<std::size_t>(m)] = true;
    }
  const body::MarkerMapping mapping = body::map_markers(static_trial.labels, model.marker_names());
  std::vector<std::pair<long, body::Pose>> poses;
  for (long k = 0; k < static_trial.frame_count(); k += 10)
    poses.emplace_back(k, static_trial.truth[static_cast<std::size_t>(k)]);
  for (long k = 0; k < moving.frame_count(); k += 4)
    poses.emplace_back(static_trial.frame_count() + k, moving.truth[static_cast<std::size_t>(k)]);
  calibration::CalibrationOptions options;  // the default offset prior and shrinkage
  options.estimate_segment_scales = false;
  options.static_pose_sd_rad = 0.5 * kPi / 180.0;  // held exactly, as for markers placed by their motion
  options.static_frames = static_trial.frame_count();
  options.static_distinct_mm = 5.0;  // the noise alone moves no marker that far: one posture
  // The feet's turn left (degrees): the largest rotation angle that maps the calibrated foot offsets
  // onto the true ones about the ankle (Kabsch without translation).
  const auto turn_left_deg = [&](const std::vector<bool>& flags) {
    calibration::CalibrationOptions o = options;
    o.placed_by_motion = flags;
    const body::BodyModel calibrated =
        calibration::adjust_subject_at_poses(model, mapping, fast_options(), both, poses, o).model;
    double largest = 0;
    for (const std::string segment : {"LA", "RA"}) {
      Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
      for (const int m : body::markers_on_segment(model, segment))
        h += subject.model.markers[static_cast<std::size_t>(m)].offset *
             calibrated.markers[static_cast<std::size_t>(m)].offset.transpose();
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
      largest = std::max(largest, Eigen::AngleAxisd(r).angle() * 180.0 / kPi);
    }
    return largest;
  };
  const double named = turn_left_deg({}), flagged = turn_left_deg(placed);
  std::cout << "feet turned 10 deg: " << named << " deg left as named markers, " << flagged
            << " deg flagged as placed by their motion\n";
  // Measured: 6.6 degrees left as named markers (the set's turn half kept), 0.2 flagged as placed.
  EXPECT_GT(named, 3.0);
  EXPECT_LT(flagged, 0.3 * named);
  options.placed_by_motion = std::vector<bool>(3, true);
  EXPECT_THROW(calibration::adjust_subject_at_poses(model, mapping, fast_options(), both, poses, options),
               std::invalid_argument);
  options.placed_offset_prior_sd_mm = 0;
  EXPECT_THROW(options.validate(), std::invalid_argument);
}

// The weak-direction shrinkage (CalibrationOptions::weak_direction_shrink = c) keeps the fraction
// mu / (mu + c) of the data's step along a direction whose share of information surviving the
// poses' elimination is mu, and leaves the length factors free. A subject without soft tissue and
// placement errors differs from the model in one marker of the chest (8 on that segment), moved
// by 12 mm, and in one bone (the left thigh), 5 % longer. A single marker's displacement is partly absorbed
// by the segment's rigid motion (6 of its 24 coordinates), so mu lies between about 0.7 and 1: with c = 1 the
// marker moves between 0.7 / 1.7 = 0.41 and 1 / 2 of the way, with c = 0 all of it. A huge c keeps every
// offset at the marker set, and the bone's length is still recovered.
TEST(SubjectCalibration, WeakDirectionShrinkageKeepsTheShareMuOverMuPlusC) {
  S2KF_SKIP_UNDER_SANITIZERS();
  sim::SubjectOptions exact;
  exact.placement_sd_mm = 0;
  exact.segment_scale_sd = 0;
  exact.soft_tissue_mm = 0;
  exact.noise_sd_mm = 0.1;
  const body::BodyModel model = body::mmm_body_model(1750);
  sim::Subject subject = sim::make_subject(model, exact, 3);
  const int moved = model.marker_index("LBAK");
  const Eigen::Vector3d displacement(0, 12, 0);
  subject.model.markers[static_cast<std::size_t>(moved)].offset += displacement;
  const int longer = model.joint_index("LKx");  // the thigh: the knee's offset from the hip
  subject.model.joints[static_cast<std::size_t>(longer)].translation *= 1.05;
  const sim::Recording recording = test_support::sweep_recording(subject, 3, 400, 5.0);
  const auto calibrated = [&](double c) {
    calibration::CalibrationOptions options;
    options.final_pass = false;
    options.weak_direction_shrink = c;
    return calibration::calibrate_subject(model, body::map_markers(recording.labels, model.marker_names()),
                                          fast_options(), recording, test::tracker_samples(fast_options()),
                                          options);
  };
  const auto fraction_moved = [&](const calibration::SubjectCalibration& calibration) {
    const Eigen::Vector3d step = calibration.model.markers[static_cast<std::size_t>(moved)].offset -
                                 model.markers[static_cast<std::size_t>(moved)].offset;
    return step.dot(displacement) / displacement.squaredNorm();
  };
  const auto length_factor = [&](const calibration::SubjectCalibration& calibration) {
    return calibration.model.joints[static_cast<std::size_t>(longer)].translation.norm() /
           model.joints[static_cast<std::size_t>(longer)].translation.norm();
  };
  const calibration::SubjectCalibration none = calibrated(0), one = calibrated(1), huge = calibrated(1e6);
  double largest_offset_move = 0;
  for (std::size_t m = 0; m < model.markers.size(); ++m)
    largest_offset_move =
        std::max(largest_offset_move, (huge.model.markers[m].offset - model.markers[m].offset).norm());
  std::cout << "marker moved " << fraction_moved(none) << " / " << fraction_moved(one) << " / "
            << fraction_moved(huge) << " of the way, thigh length factor " << length_factor(none) << " / "
            << length_factor(one) << " / " << length_factor(huge)
            << " (c = 0 / 1 / 1e6); largest offset move at 1e6 " << largest_offset_move << " mm\n";
  EXPECT_NEAR(fraction_moved(none), 1.0, 0.05);
  EXPECT_GT(fraction_moved(one), 0.41);
  EXPECT_LT(fraction_moved(one), 0.5);
  EXPECT_LT(largest_offset_move, 0.01);
  for (const auto* calibration : {&none, &one, &huge}) EXPECT_NEAR(length_factor(*calibration), 1.05, 0.01);
}

TEST(SubjectCalibration, LowersJointAngleErrorAndKeepsJointsInsideLimits) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const Synthetic s = make_synthetic(300, 8.0, 11);  // default soft tissue
  const body::BodyModel model = body::mmm_body_model(1750);
  const calibration::SubjectCalibration calibration = calibrate(model, s);
  const io::MotionTable truth = truth_table(s, model);
  const evaluation::TruthComparison plain =
      evaluation::compare_with_truth(model, track_all(model, s, fast_options()), truth, 50);
  const evaluation::TruthComparison calibrated =
      evaluation::compare_with_truth(model, track_all(calibration.model, s, fast_options()), truth, 50);
  std::cout << "all-joint RMS " << plain.all_joint_rms_deg << " -> " << calibrated.all_joint_rms_deg
            << " deg; segment orientation RMS " << plain.segment_orientation_rms_deg << " -> "
            << calibrated.segment_orientation_rms_deg << " deg\n";
  EXPECT_LT(calibrated.all_joint_rms_deg, plain.all_joint_rms_deg);
  EXPECT_EQ(calibrated.joint_limit_violations, 0);
}

TEST(SubjectCalibration, RejectsInputsThatCannotBeCalibrated) {
  const body::BodyModel model = body::mmm_body_model(1750);
  const body::MarkerMapping mapping = body::map_markers(model.marker_names(), model.marker_names());
  const SampleSet& samples = test::tracker_samples(fast_options());
  MarkerSequence none;
  none.labels = model.marker_names();
  none.rate_hz = 100;
  none.resize(0);
  EXPECT_THROW(calibration::calibrate_subject(model, mapping, fast_options(), none, samples),
               std::invalid_argument);
  calibration::CalibrationOptions options;
  options.iterations = 0;
  MarkerSequence one = none;
  one.resize(1);
  one.set_frame(0, body::marker_positions(model, body::zero_pose(model)),
                FrameVisibility::Constant(model.marker_count(), true));
  EXPECT_THROW(calibration::calibrate_subject(model, mapping, fast_options(), one, samples, options),
               std::invalid_argument);
  for (const double shrink : {-0.1, std::numeric_limits<double>::quiet_NaN(), HUGE_VAL}) {
    calibration::CalibrationOptions shrinking;
    shrinking.weak_direction_shrink = shrink;
    try {
      calibration::calibrate_subject(model, mapping, fast_options(), one, samples, shrinking);
      ADD_FAILURE() << "a weak-direction shrinkage of " << shrink << " was accepted";
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find("weak-direction shrinkage"), std::string::npos)
          << error.what();
    }
  }
  body::MarkerMapping short_mapping = mapping;
  short_mapping.point_of_marker.pop_back();
  EXPECT_THROW(calibration::calibrate_subject(model, short_mapping, fast_options(), one, samples),
               std::invalid_argument);
}

// Threads split the tracking pass by stretch and the bundle adjustment's frames into fixed chunks
// whose sums are added in chunk order: the calibrated subject must be the same to the last bit
// with one thread and with three (a count that divides neither the 2 stretches nor the 8 chunks).
TEST(SubjectCalibration, ResultDoesNotDependOnTheThreadCount) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const Synthetic s = make_synthetic(300, 8.0, 5);
  const body::BodyModel model = body::mmm_body_model(1750);
  const body::MarkerMapping mapping = body::map_markers(s.recording.labels, model.marker_names());
  calibration::CalibrationOptions options;
  options.final_pass = false;
  options.restart_frames = {150};
  options.threads = 1;
  const calibration::SubjectCalibration one = calibration::calibrate_subject(
      model, mapping, fast_options(), s.recording, test::tracker_samples(fast_options()), options);
  options.threads = 3;
  const calibration::SubjectCalibration three = calibration::calibrate_subject(
      model, mapping, fast_options(), s.recording, test::tracker_samples(fast_options()), options);
  ASSERT_EQ(one.passes.size(), three.passes.size());
  EXPECT_GT(one.passes.front().bundle_iterations, 1);
  EXPECT_EQ(one.passes.front().bundle_iterations, three.passes.front().bundle_iterations);
  EXPECT_EQ(one.passes.front().frames_used, three.passes.front().frames_used);
  EXPECT_EQ(one.mean_marker_distance_before_mm, three.mean_marker_distance_before_mm);
  EXPECT_EQ(one.passes.front().rms_after_mm, three.passes.front().rms_after_mm);
  for (int m = 0; m < model.marker_count(); ++m)
    EXPECT_EQ(one.model.markers[static_cast<std::size_t>(m)].offset,
              three.model.markers[static_cast<std::size_t>(m)].offset);
  for (int j = 0; j < model.joint_count(); ++j)
    EXPECT_EQ(one.model.joints[static_cast<std::size_t>(j)].translation,
              three.model.joints[static_cast<std::size_t>(j)].translation);
  // ... and it moved the subject (the comparison is not between two untouched models).
  double moved = 0;
  for (int m = 0; m < model.marker_count(); ++m)
    moved = std::max(moved, (one.model.markers[static_cast<std::size_t>(m)].offset -
                             model.markers[static_cast<std::size_t>(m)].offset)
                                .norm());
  EXPECT_GT(moved, 1.0);
  options.threads = 0;
  EXPECT_THROW(calibration::calibrate_subject(model, mapping, fast_options(), s.recording,
                                              test::tracker_samples(fast_options()), options),
               std::invalid_argument);
}

// Per-marker noise (a marker set's noise_mm) in the tracker: equal values change nothing, and a
// marker given a huge noise no longer moves the estimate when its measurements go wrong.
TEST(TrackerMarkerNoise, NoisyMarkerBarelyMovesTheEstimate) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const Synthetic s = make_synthetic(80, 8.0, 3);
  const body::BodyModel model = body::mmm_body_model(1750);
  const track::TrackerOptions plain = fast_options();
  const auto count = static_cast<std::size_t>(model.marker_count());
  const auto max_difference = [](const io::MotionTable& a, const io::MotionTable& b) {
    EXPECT_TRUE(a.values.allFinite() && b.values.allFinite());
    return (a.values - b.values).cwiseAbs().maxCoeff();
  };
  const io::MotionTable reference = track_all(model, s, plain);

  track::TrackerOptions same = plain;
  same.marker_noise_mm_per_marker.assign(count, plain.marker_noise_mm);
  EXPECT_EQ(max_difference(track_all(model, s, same), reference), 0.0);

  // The left knee marker slips 30 mm from frame 10 on (after the tracker has started).
  const int loose_marker = model.marker_index("LKNE");
  Synthetic slipped = s;
  for (std::size_t k = 10; k < slipped.points.size(); ++k)
    slipped.points[k].col(loose_marker) += Eigen::Vector3d(30, 0, 0);  // recording order = model order
  track::TrackerOptions loose = plain;
  loose.marker_noise_mm_per_marker.assign(count, std::numeric_limits<double>::quiet_NaN());
  loose.marker_noise_mm_per_marker[static_cast<std::size_t>(loose_marker)] = 1e5;
  const double effect_plain = max_difference(track_all(model, slipped, plain), reference);
  const double effect_loose = max_difference(track_all(model, slipped, loose), track_all(model, s, loose));
  std::cout << "effect of the slipped marker: " << effect_plain << " with the common noise, " << effect_loose
            << " with 1e5 mm on that marker\n";
  // How far the slip moves the estimate depends on the samples' rounding (2.1 built by GCC, 0.9 by
  // Clang); with the marker's huge noise it is a thousandth of that either way.
  EXPECT_GT(effect_plain, 0.5);
  EXPECT_LT(effect_loose, 1e-3 * effect_plain);

  track::TrackerOptions wrong = plain;
  wrong.marker_noise_mm_per_marker.assign(count - 1, 10.0);
  EXPECT_THROW(track::Tracker(model, body::map_markers(s.recording.labels, model.marker_names()), wrong,
                              100.0, test::tracker_samples(wrong)),
               std::invalid_argument);
  wrong.marker_noise_mm_per_marker.assign(count, -1.0);
  EXPECT_THROW(wrong.validate(), std::invalid_argument);
}

}  // namespace

namespace {

// The recovery over three more subjects with 1200 frames each (measured: offsets 2.8-4.2 mm, worst
// bone length 0.97-2.8 %, seed 3's; seeds 4-5 give 2.6-2.8 mm and 1.2-1.9 %), about 7 s.
TEST(SubjectCalibration, RecoveryOverSeeds) {
  S2KF_SKIP_UNDER_SANITIZERS();
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const Synthetic s = make_synthetic(1200, 0.0, seed);
    const calibration::SubjectCalibration calibration = calibrate(body::mmm_body_model(1750), s);
    const double offsets = offset_error(calibration.model, s.subject);
    const double lengths = worst_scale_error(calibration, s.subject, 1.0);
    std::cout << "seed " << seed << ": offset error " << offsets << " mm, worst length error "
              << 100 * lengths << " %\n";
    EXPECT_LT(offsets, 5.0);
    EXPECT_LT(lengths, 0.035);
  }
}

}  // namespace
