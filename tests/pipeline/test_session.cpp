// The tracking pipeline (pipeline/session.hpp): a session prepared from a C3D file streamed frame by
// frame equals one prepared from the same recording in memory, rows handed to a sink equal the
// kept table, and bad recordings are refused with a sentence before any tracking.
#include "test_files.hpp"
#include "tracker_samples.hpp"

#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/state_chart.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>
#include "address_sanitizer.hpp"

namespace {

using namespace s2kf;

using test_support::data_file;

body::MarkerSet kit_like_set() { return body::model_marker_set(body::mmm_body_model(1000)); }

TEST(Session, FileAndMemorySourcesGiveTheSameSessionAndRun) {
  S2KF_SKIP_UNDER_SANITIZERS();
  c3d::C3dFrameSource file(data_file("handstand.c3d"));
  const MarkerSequence all = c3d::read_c3d(data_file("handstand.c3d"));
  const MarkerSequence head = all.frames(0, 150);
  SequenceFrameSource memory(head);
  ASSERT_EQ(file.labels(), head.labels);
  pipeline::SessionOptions options;
  options.calibration_frames = 150;
  options.calibration_windows = 1;  // the first 150 frames of the file: the memory source's frames
  const SampleSet& samples = test::tracker_samples();
  const pipeline::Session from_file = pipeline::prepare_session(file, kit_like_set(), options, samples);
  // The height estimate reads spread frames of the whole file; give the memory source the same.
  options.height_mm = from_file.height_mm;
  const pipeline::Session from_memory = pipeline::prepare_session(memory, kit_like_set(), options, samples);
  EXPECT_EQ(from_file.markers_used(), 50);
  ASSERT_TRUE(from_file.calibration.has_value());
  ASSERT_TRUE(from_memory.calibration.has_value());
  EXPECT_GT(from_file.height_mm, 1000);
  EXPECT_NE(from_file.height_source.find("rigid marker pairs"), std::string::npos);
  for (int m = 0; m < from_file.model.marker_count(); ++m)
    EXPECT_EQ(from_file.model.markers[m].offset, from_memory.model.markers[m].offset) << m;

  // A sink receives exactly the rows the run would keep.
  std::vector<Eigen::VectorXd> rows;
  pipeline::RunHooks hooks;
  hooks.sink = [&](const track::TrackedFrame& f) { rows.push_back(f.values); };
  const track::TrackingRun streamed = pipeline::run_session(from_memory, memory, samples, {}, hooks);
  const track::TrackingRun kept = pipeline::run_session(from_memory, memory, samples);
  ASSERT_EQ(rows.size(), 150u);
  ASSERT_EQ(kept.motion.frames(), 150);
  for (Eigen::Index r = 0; r < 150; ++r)
    EXPECT_EQ(
        (rows[static_cast<std::size_t>(r)] - kept.motion.values.row(r).transpose()).cwiseAbs().maxCoeff(),
        0.0)
        << r;
  EXPECT_EQ(streamed.mean_marker_distance, kept.mean_marker_distance);
  EXPECT_TRUE(std::isfinite(pipeline::calibrated_distance_mm(from_memory, kept)));
}

TEST(Session, RefusesRecordingsItCannotTrack) {
  MarkerSequence unknown;
  unknown.labels = {"A", "B", "C"};
  unknown.rate_hz = 100;
  unknown.resize(10);
  SequenceFrameSource source(unknown);
  const SampleSet& samples = test::tracker_samples();
  try {
    pipeline::prepare_session(source, kit_like_set(), {}, samples);
    FAIL() << "labels of no marker were accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("none of its 3 point labels"), std::string::npos) << e.what();
  }
  MarkerSequence no_rate = c3d::read_c3d(data_file("handstand.c3d")).frames(0, 5);
  no_rate.rate_hz = 0;
  SequenceFrameSource zero(no_rate);
  EXPECT_THROW(pipeline::prepare_session(zero, kit_like_set(), {}, samples), std::invalid_argument);

  // A recording in metres read as mm: a body of about 1.7 mm is not a person's, and a given height
  // (what the old message advised) does not hide it: the rigid marker pairs still measure 1.7 mm.
  MarkerSequence metres = c3d::read_c3d(data_file("handstand.c3d")).frames(0, 20);
  metres.positions /= 1000;
  SequenceFrameSource tiny(metres);
  for (const double given : {0.0, 1750.0}) {
    pipeline::SessionOptions options;
    options.height_mm = given;
    try {
      pipeline::prepare_session(tiny, kit_like_set(), options, samples);
      FAIL() << "a recording in metres was accepted with --height " << given;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("in metres, not millimetres"), std::string::npos) << e.what();
    }
  }
}

TEST(Session, UnitsProblemComparesTheRigidPairsWithTheHeight) {
  // Estimated from the pairs themselves: only a body outside 300..3000 mm is refused.
  EXPECT_EQ(calibration::units_problem(1700, 1700, "estimated from 12 rigid marker pairs"), "");
  EXPECT_NE(calibration::units_problem(1.7, 1.7, "estimated from 12 rigid marker pairs").find("in metres"),
            std::string::npos);
  EXPECT_NE(
      calibration::units_problem(170, 170, "estimated from 3 rigid marker pairs").find("in centimetres"),
      std::string::npos);
  // A given height: the pairs must agree within a factor of 2 (a child, a mis-scaled set pass).
  EXPECT_EQ(calibration::units_problem(1300, 1750, "given"), "");
  EXPECT_NE(calibration::units_problem(1.75, 1750, "given").find("but the height given is 1750 mm"),
            std::string::npos);
  EXPECT_NE(calibration::units_problem(68.9, 1750, "given").find("in inches"), std::string::npos);
  // A factor no unit explains is still refused, without naming a unit.
  EXPECT_NE(calibration::units_problem(500, 1750, "given").find("not in millimetres"), std::string::npos);
}

TEST(Session, StopsAtCoordinatesBeyondAKilometre) {
  MarkerSequence recording = c3d::read_c3d(data_file("handstand.c3d")).frames(0, 40);
  recording.frame(30).col(3) = Eigen::Vector3d(5e6, 0, 0);
  SequenceFrameSource source(recording);
  pipeline::SessionOptions options;
  options.calibrate = false;
  options.height_mm = 1750;
  const pipeline::Session session =
      pipeline::prepare_session(source, kit_like_set(), options, test::tracker_samples());
  try {
    pipeline::run_session(session, source, test::tracker_samples());
    FAIL() << "a point 5 km away was tracked";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("frame 30"), std::string::npos) << e.what();
  }
}

// The chart: folding keeps every joint angle and flips the covariance sign of reflected states;
// to_previous_chart undoes a fold and a reference change.
TEST(StateChart, FoldingKeepsAnglesAndItsInverseRestoresTheState) {
  const body::BodyModel model = body::mmm_body_model(1750);
  const body::BoundedJoints joints(model);
  const int n = 6 + model.joint_count();
  Eigen::VectorXd mean = Eigen::VectorXd::LinSpaced(n, -7.0, 9.0);
  mean.segment<3>(3) << 0.1, -0.2, 0.05;
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Identity(n, n);
  covariance(6, 7) = covariance(7, 6) = 0.5;
  const Eigen::VectorXd before = mean;
  const Eigen::MatrixXd covariance_before = covariance;
  track::fold_joint_parameters(mean, covariance);
  for (Eigen::Index k = 6; k < n; ++k) EXPECT_LE(std::abs(mean(k)), kPi / 2 + 1e-12) << k;
  const Eigen::VectorXd angles_before = joints.angles(before.tail(model.joint_count()));
  const Eigen::VectorXd angles_after = joints.angles(mean.tail(model.joint_count()));
  EXPECT_LT((angles_before - angles_after).cwiseAbs().maxCoeff(), 1e-12);
  // Exactly the reflected states changed sign in the covariance.
  const bool reflected6 = std::abs(std::remainder(before(6), 2 * kPi)) > kPi / 2;
  const bool reflected7 = std::abs(std::remainder(before(7), 2 * kPi)) > kPi / 2;
  EXPECT_EQ(covariance(6, 7), (reflected6 != reflected7 ? -1 : 1) * covariance_before(6, 7));

  // Back into the chart before: the same reference, the unfolded values as the previous mean.
  const Eigen::Matrix3d reference = body::rotation_exp(Eigen::Vector3d(0.3, 0.1, -0.4));
  Eigen::VectorXd restored = mean;
  Eigen::MatrixXd restored_covariance = covariance;
  track::to_previous_chart(reference, reference, before, restored, restored_covariance);
  EXPECT_LT((restored.tail(model.joint_count()) - before.tail(model.joint_count())).cwiseAbs().maxCoeff(),
            1e-9);
  EXPECT_LT((restored_covariance - covariance_before).cwiseAbs().maxCoeff(), 1e-15);
  // A reference change moves the orientation error so that the rotation stays the same.
  const Eigen::Matrix3d next = reference * body::rotation_exp(Eigen::Vector3d(0.02, 0.0, 0.01));
  Eigen::VectorXd moved = mean;
  track::to_previous_chart(reference, next, before, moved, restored_covariance);
  EXPECT_LT((track::chart_rotation(reference, moved.segment<3>(3)) -
             track::chart_rotation(next, mean.segment<3>(3)))
                .cwiseAbs()
                .maxCoeff(),
            1e-12);
}

// With rates (the constant-velocity state), a reflected Theta's rate changes sign with it and the
// orientation rate turns with the reference; going back with to_previous_chart restores both.
TEST(StateChart, RatesFollowTheFoldAndTheReferenceTurn) {
  const int n = 46;
  Eigen::VectorXd mean = Eigen::VectorXd::LinSpaced(2 * n, -3.0, 4.0);
  mean.segment<3>(3).setZero();
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Identity(2 * n, 2 * n);
  covariance(6, n + 6) = covariance(n + 6, 6) = 0.3;
  const Eigen::VectorXd before = mean;
  const Eigen::MatrixXd covariance_before = covariance;
  track::fold_joint_parameters(mean, covariance, true);
  for (Eigen::Index k = 6; k < n; ++k) {
    const bool reflected = std::abs(std::remainder(before(k), 2 * kPi)) > kPi / 2;
    EXPECT_EQ(mean(n + k), reflected ? -before(n + k) : before(n + k)) << k;
  }
  EXPECT_EQ(mean.segment<3>(n), before.segment<3>(n));           // root rates untouched by the fold
  EXPECT_EQ(covariance(6, n + 6), covariance_before(6, n + 6));  // state and its rate flip together
  // The reference turns by D (R_next = R_previous D): in the new chart the rate is D^T omega.
  const Eigen::Matrix3d turn = body::rotation_exp(Eigen::Vector3d(0.2, -0.1, 0.3));
  Eigen::VectorXd turned = mean;
  Eigen::MatrixXd turned_covariance = covariance;
  track::turn_orientation_rate(turned, turned_covariance, turn);
  EXPECT_LT((turned.segment<3>(n + 3) - turn.transpose() * mean.segment<3>(n + 3)).norm(), 1e-12);
  const Eigen::Matrix3d reference = Eigen::Matrix3d::Identity();
  track::to_previous_chart(reference, reference * turn, before, turned, turned_covariance, true);
  EXPECT_LT((turned.tail(n) - before.tail(n)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((turned_covariance - covariance_before).cwiseAbs().maxCoeff(), 1e-12);
}

// A joint at its limit (Theta at -pi/2, where the sine's slope vanishes) or spread far beyond the
// sine's branch is brought back where the markers can move it: the mean a margin inside, the SD
// capped by scaling its row and column (so the covariance stays positive definite and the
// correlations stay as they were); the root and the joints inside the bounds are untouched.
TEST(StateChart, JointParametersAreKeptWhereTheMarkersCanMoveThem) {
  const int n = 10;
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(n);
  mean << 5.0, -3.0, 2.0, 0.1, 0.2, 0.3, -kPi / 2, 1.0, kPi / 2 - 0.01, 0.2;
  Eigen::MatrixXd shape = Eigen::MatrixXd::Random(n, n);
  Eigen::MatrixXd covariance = shape * shape.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
  covariance(9, 9) += 4.0;  // SD above 2
  const Eigen::VectorXd before = mean;
  const Eigen::MatrixXd covariance_before = covariance;
  track::keep_joint_parameters_learnable(mean, covariance, 0.05, 0.5);
  EXPECT_EQ(mean.head(6), before.head(6));
  EXPECT_DOUBLE_EQ(mean(6), -kPi / 2 + 0.05);
  EXPECT_EQ(mean(7), before(7));
  EXPECT_DOUBLE_EQ(mean(8), kPi / 2 - 0.05);
  EXPECT_EQ(mean(9), before(9));
  for (Eigen::Index k = 6; k < n; ++k) {
    EXPECT_LE(covariance(k, k), 0.25 * (1 + 1e-12)) << k;
    if (covariance_before(k, k) > 0.25) {
      EXPECT_NEAR(covariance(k, k), 0.25, 1e-12) << k;
    }
  }
  const auto correlation = [](const Eigen::MatrixXd& c, int i, int j) {
    return c(i, j) / std::sqrt(c(i, i) * c(j, j));
  };
  EXPECT_NEAR(correlation(covariance, 9, 2), correlation(covariance_before, 9, 2), 1e-12);
  EXPECT_NEAR(correlation(covariance, 9, 7), correlation(covariance_before, 9, 7), 1e-12);
  EXPECT_EQ(covariance.topLeftCorner(6, 6), covariance_before.topLeftCorner(6, 6));
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(covariance).info(), Eigen::Success);
  // 0 disables each bound.
  Eigen::VectorXd same = before;
  Eigen::MatrixXd same_covariance = covariance_before;
  track::keep_joint_parameters_learnable(same, same_covariance, 0, 0);
  EXPECT_EQ(same, before);
  EXPECT_EQ(same_covariance, covariance_before);
}

// The calibration's tracking pass can take its own, smaller sample set: the bundle adjustment
// refines the poses that pass starts it from, so on this recording the subject fits as well.
TEST(Session, CalibrationTracksWithItsOwnSampleSet) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const MarkerSequence head = c3d::read_c3d(data_file("handstand.c3d")).frames(0, 200);
  SequenceFrameSource source(head);
  pipeline::SessionOptions options;
  options.height_mm = 1705;
  const SampleSet& samples = test::tracker_samples();
  const pipeline::Session own = pipeline::prepare_session(source, kit_like_set(), options, samples);
  options.calibration_samples = test::tracker_samples(93);
  const pipeline::Session small = pipeline::prepare_session(source, kit_like_set(), options, samples);
  ASSERT_TRUE(own.calibration.has_value());
  ASSERT_TRUE(small.calibration.has_value());
  EXPECT_EQ(own.calibration_sample_count, samples.count());
  EXPECT_EQ(small.calibration_sample_count, 93);
  // The tracker's per-marker noise follows the calibration's residuals (noise_from_calibration).
  const std::vector<double>& residual = own.calibration->marker_residual_rms_mm;
  ASSERT_EQ(residual.size(), static_cast<std::size_t>(own.model.marker_count()));
  EXPECT_EQ(own.tracker.marker_noise_mm_per_marker,
            pipeline::marker_noise_from_residuals(residual, own.tracker.marker_noise_mm, {}));
  int finite = 0;
  for (double r : residual) finite += std::isfinite(r) ? 1 : 0;
  EXPECT_EQ(finite, own.mapping.markers_used());
  // Another pass, so another start for the bundle adjustment: the subject moves a little...
  double largest_change = 0;
  for (int m = 0; m < own.model.marker_count(); ++m)
    largest_change =
        std::max(largest_change, (own.model.markers[m].offset - small.model.markers[m].offset).norm());
  EXPECT_GT(largest_change, 0.0);
  EXPECT_LT(largest_change, 1.0);  // mm; measured 0.06
  // ...and both fit the recording about as well (same tracker, 301 samples, over the 200 frames).
  const track::TrackingRun own_run = pipeline::run_session(own, source, samples);
  const track::TrackingRun small_run = pipeline::run_session(small, source, samples);
  const double own_mm = track::mean_from(own_run.mean_marker_distance, 20);
  const double small_mm = track::mean_from(small_run.mean_marker_distance, 20);
  EXPECT_LT(own_mm, 7.0);  // measured 5.20 mm, both
  EXPECT_LT(small_mm, 1.01 * own_mm) << own_mm;

  // A set for another dimension is refused with a sentence, calibration failures allowed or not.
  options.calibration_samples.points = Eigen::MatrixXd::Zero(10, 40);
  options.calibration_samples.weights = Eigen::VectorXd::Constant(40, 1.0 / 40);
  try {
    pipeline::prepare_session(source, kit_like_set(), options, samples);
    FAIL() << "a 10-dimensional calibration sample set was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("calibration's sample set has 10 dimensions but the tracker's 46"),
              std::string::npos)
        << e.what();
  }
}

// Each marker's noise: the common noise times its residual over the median residual, within 0.5-2
// times; a marker with its own noise keeps it, one without a residual gets NaN (the common noise).
TEST(Session, MarkerNoiseFollowsTheCalibrationResiduals) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Median of the finite residuals {1, 2, 4, 8, 16} is 4.
  const std::vector<double> residual{2, 4, 8, nan, 16, 1};
  const std::vector<double> noise = pipeline::marker_noise_from_residuals(residual, 10.0, {});
  ASSERT_EQ(noise.size(), residual.size());
  EXPECT_DOUBLE_EQ(noise[0], 5.0);
  EXPECT_DOUBLE_EQ(noise[1], 10.0);
  EXPECT_DOUBLE_EQ(noise[2], 20.0);
  EXPECT_TRUE(std::isnan(noise[3]));
  EXPECT_DOUBLE_EQ(noise[4], 20.0);  // 4 times the median, clamped to 2
  EXPECT_DOUBLE_EQ(noise[5], 5.0);   // a quarter, clamped to a half
  const std::vector<double> own{nan, 3.0, nan, 7.0};
  const std::vector<double> kept = pipeline::marker_noise_from_residuals(residual, 10.0, own);
  EXPECT_DOUBLE_EQ(kept[1], 3.0);
  EXPECT_DOUBLE_EQ(kept[3], 7.0);  // its own noise, though it had no residual
  EXPECT_DOUBLE_EQ(kept[2], 20.0);
  // No residual at all: the set's own noise, unchanged.
  EXPECT_EQ(pipeline::marker_noise_from_residuals({nan, nan}, 10.0, {}), std::vector<double>{});
}

// Calibration reads the whole of a short recording, and spread stretches of a long one.
TEST(Session, CalibrationStretchesCoverTheRecordingWithinTheBudget) {
  using Stretches = std::vector<std::pair<std::int64_t, std::int64_t>>;
  EXPECT_EQ(pipeline::calibration_stretches(800, 1200, 4), (Stretches{{0, 800}}));
  EXPECT_EQ(pipeline::calibration_stretches(4000, 1200, 4),
            (Stretches{{0, 300}, {1233, 300}, {2466, 300}, {3700, 300}}));
  EXPECT_EQ(pipeline::calibration_stretches(4000, 1200, 1), (Stretches{{0, 1200}}));
  std::int64_t total = 0;
  for (const auto& [first, count] : pipeline::calibration_stretches(1'000'000, 1200, 4)) total += count;
  EXPECT_EQ(total, 1200);  // bounded, whatever the length
}

}  // namespace

namespace {

// A static trial whose file orders its points otherwise, names one the recording does not have and
// lacks one the recording has: its frames come out in the recording's point order, the marker it
// lacks missing, the one it adds dropped. One showing fewer than 3 of the recording's markers is
// refused with a sentence.
TEST(Session, AStaticTrialIsPutInTheRecordingsPointOrder) {
  const body::MarkerSet set = kit_like_set();
  const std::vector<std::string> names = body::mmm_body_model(1000).marker_names();
  const std::vector<std::string> recording_labels{names[0], names[1], names[2], names[3]};
  const body::MarkerMapping mapping = body::map_marker_set(recording_labels, set);
  MarkerSequence trial;
  trial.labels = {"NOT_A_MARKER", names[2], names[0], names[1]};  // names[3] missing
  trial.rate_hz = 100;
  trial.resize(2);
  for (Eigen::Index f = 0; f < 2; ++f) {
    Eigen::Matrix3Xd points(3, 4);
    for (Eigen::Index p = 0; p < 4; ++p) points.col(p) = Eigen::Vector3d::Constant(10.0 * p + f);
    trial.set_frame(f, points, FrameVisibility::Constant(4, true));
  }
  const MarkerSequence ordered = pipeline::static_trial_in_recording_order(trial, set, mapping, 4);
  ASSERT_EQ(ordered.point_count(), 4);
  ASSERT_EQ(ordered.frame_count(), 2);
  EXPECT_EQ(ordered.frame(1).col(0), Eigen::Vector3d::Constant(21.0));  // names[0]: the trial's point 2
  EXPECT_EQ(ordered.frame(1).col(1), Eigen::Vector3d::Constant(31.0));
  EXPECT_EQ(ordered.frame(0).col(2), Eigen::Vector3d::Constant(10.0));
  EXPECT_FALSE(ordered.visible(3, 0));
  EXPECT_TRUE(ordered.frame(0).col(3).hasNaN());
  trial.labels = {"A", "B", names[0], names[1]};
  EXPECT_THROW(pipeline::static_trial_in_recording_order(trial, set, mapping, 4), std::invalid_argument);
}

}  // namespace
