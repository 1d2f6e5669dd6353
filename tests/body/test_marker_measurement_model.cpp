// The tracker's marker measurement model against forward kinematics, in both orientation modes.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_measurement_model.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <random>

// Counts heap allocations while `counting` is set, to check the model allocates only on its first call.
namespace {
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
}  // namespace

// The replacements pair malloc with free; GCC cannot see that through the inlined operators.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void* operator new(std::size_t size) {
  if (counting) ++allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

using namespace s2kf::body;

Eigen::MatrixXd random_states(std::mt19937& rng, Eigen::Index count, double orientation_scale) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd states(kStateDimension, count);
  for (Eigen::Index i = 0; i < count; ++i) {
    for (int k = 0; k < 3; ++k) states(k, i) = 500 * normal(rng);
    for (int k = 3; k < 6; ++k) states(k, i) = orientation_scale * normal(rng);
    for (int k = 6; k < kStateDimension; ++k) states(k, i) = 1.5 * normal(rng);
  }
  return states;
}

Eigen::VectorXd stacked(const Eigen::Matrix3Xd& m) {
  return Eigen::Map<const Eigen::VectorXd>(m.data(), m.size());
}

TEST(MarkerMeasurementModel, RollPitchYawModeEqualsForwardKinematicsOfTheBoundedPose) {
  const BodyModel body = mmm_body_model(1810);
  MarkerMeasurementModel h(body);
  ASSERT_EQ(h.state_dimension(), 46);
  ASSERT_EQ(h.measurement_dimension(), 150);
  std::mt19937 rng(1);
  const Eigen::MatrixXd states = random_states(rng, 301, 1.0);
  Eigen::MatrixXd predictions(150, 301);
  h(states, predictions);
  const BoundedJoints bounded(body);
  for (Eigen::Index i = 0; i < states.cols(); ++i) {
    const Eigen::VectorXd angles = bounded.angles(states.col(i).tail<kJointCount>());
    ASSERT_TRUE(bounded.within_limits(angles));
    const Eigen::Matrix3Xd expected = marker_positions(
        body, states.col(i).head<3>(), rotation_from_rpy(states.col(i).segment<3>(3)), angles);
    EXPECT_LT((predictions.col(i) - stacked(expected)).cwiseAbs().maxCoeff(), 1e-9) << i;
    EXPECT_LT(
        (stacked(marker_positions(body, h.pose(states.col(i)))) - predictions.col(i)).cwiseAbs().maxCoeff(),
        1e-9);
  }
}

TEST(MarkerMeasurementModel, LocalRotationErrorModeEqualsForwardKinematicsAboutTheReference) {
  const BodyModel body = mmm_body_model();
  MarkerMeasurementModel h(body, OrientationParameterization::local_rotation_error);
  const Eigen::Matrix3d reference =
      rotation_from_rpy(Eigen::Vector3d(0.4, M_PI / 2, -1.0));  // a handstand-like attitude
  h.set_reference_orientation(reference);
  std::mt19937 rng(2);
  Eigen::MatrixXd states = random_states(rng, 130, 0.5);
  states.col(0).segment<3>(3).setZero();
  states.col(1).segment<3>(3) = Eigen::Vector3d(1e-7, -2e-6, 3e-8);  // the small-angle series
  Eigen::MatrixXd predictions(h.measurement_dimension(), states.cols());
  h(states, predictions);
  const BoundedJoints bounded(body);
  for (Eigen::Index i = 0; i < states.cols(); ++i) {
    const Eigen::Vector3d delta = states.col(i).segment<3>(3);
    const Eigen::Matrix3Xd expected =
        marker_positions(body, states.col(i).head<3>(), reference * rotation_exp(delta),
                         bounded.angles(states.col(i).tail<kJointCount>()));
    EXPECT_LT((predictions.col(i) - stacked(expected)).cwiseAbs().maxCoeff(), 1e-9) << i;
  }
}

TEST(MarkerMeasurementModel, SinglePrecisionAgreesWithDoubleToFloatRoundingAtBodyScale) {
  // The tracker's sample pipeline: float FK. Coordinates of about a metre in float carry about
  // 6e-5 mm of rounding each, and the chain of up to 8 joints adds a few roundings of the same
  // size; 1e-3 mm is far beyond that and far below the marker noise (about 10 mm).
  const BodyModel body = mmm_body_model(1750);
  for (const auto orientation :
       {OrientationParameterization::roll_pitch_yaw, OrientationParameterization::local_rotation_error}) {
    MarkerMeasurementModel twice(body, orientation), single(body, orientation);
    const Eigen::Matrix3d reference = rotation_from_rpy(Eigen::Vector3d(0.4, M_PI / 2, -1.0));
    twice.set_reference_orientation(reference);
    single.set_reference_orientation(reference);
    single.set_single_precision(true);
    std::mt19937 rng(4);
    Eigen::MatrixXd states = random_states(rng, 701, 0.5);             // three blocks
    states.col(1).segment<3>(3) = Eigen::Vector3d(1e-7, -2e-6, 3e-8);  // the small-angle series
    Eigen::MatrixXd expected(150, states.cols()), predictions(150, states.cols());
    twice(states, expected);
    single(states, predictions);
    const double worst = (predictions - expected).cwiseAbs().maxCoeff();
    EXPECT_LT(worst, 1e-3);
    EXPECT_GT(worst, 0.0);  // it did run in float
  }
}

// The filter's symmetric sample sets: columns [mean, mean + H, mean - H].
Eigen::MatrixXd symmetric_states(const Eigen::VectorXd& mean, const Eigen::MatrixXd& half,
                                 Eigen::Index origin) {
  Eigen::MatrixXd states(mean.size(), origin + 2 * half.cols());
  states.leftCols(origin).colwise() = mean;
  states.middleCols(origin, half.cols()) = half.colwise() + mean;
  states.rightCols(half.cols()) = (-half).colwise() + mean;
  return states;
}

TEST(MarkerMeasurementModel, FloatDeviationsFromTheMeanPoseKeepTheirRelativePrecision) {
  // Each sample's prediction minus the mean pose's, against the same difference of double
  // evaluations (whose rounding, about 1e-13 mm, is far below the bound): within 2e-6 of the
  // column's largest deviation, for deviations from 0.3 rad down to 1e-5 rad (about 0.01 mm at the
  // markers), where float forward kinematics of the whole pose, which rounds the lab coordinates to
  // about 1e-4 mm, is off by a large part of the deviation itself.
  const BodyModel body = mmm_body_model(1750);
  const s2kf::InstructionSet active = s2kf::active_instruction_set();
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  for (const auto orientation :
       {OrientationParameterization::roll_pitch_yaw, OrientationParameterization::local_rotation_error}) {
    MarkerMeasurementModel twice(body, orientation), deviations(body, orientation),
        whole_float(body, orientation);
    const Eigen::Matrix3d reference = rotation_from_rpy(Eigen::Vector3d(0.4, 1.3, -1.0));
    for (MarkerMeasurementModel* h : {&twice, &deviations, &whole_float})
      h->set_reference_orientation(reference);
    deviations.set_single_precision_deviations(true);
    whole_float.set_single_precision(true);
    Eigen::VectorXd mean = random_states(rng, 1, 0.2).col(0);
    mean.tail(kJointCount) = mean.tail(kJointCount).cwiseMax(-1.5).cwiseMin(1.5);  // Theta near +-pi/2 too
    for (const double scale : {0.3, 1e-2, 1e-5}) {
      for (const auto& [origin, pairs] :
           {std::pair<Eigen::Index, Eigen::Index>{1, 150}, {0, 350}}) {  // 1 and 3 blocks
        Eigen::MatrixXd half(kStateDimension, pairs);
        for (Eigen::Index k = 0; k < pairs; ++k)
          for (Eigen::Index r = 0; r < kStateDimension; ++r)
            half(r, k) = (r < 3 ? 300 : 1) * scale * normal(rng);
        const Eigen::MatrixXd states = symmetric_states(mean, half, origin);
        Eigen::MatrixXd expected(150, states.cols()), at_mean(150, 1), whole(150, states.cols());
        twice(states, expected);
        twice(mean, at_mean);
        whole_float(states, whole);
        for (const auto set :
             {s2kf::InstructionSet::sse2, s2kf::InstructionSet::avx2, s2kf::InstructionSet::avx512}) {
          if (set > s2kf::supported_instruction_set() || set < s2kf::compiled_instruction_set()) continue;
          s2kf::use_instruction_set(set);
          Eigen::MatrixXd predictions(150, states.cols());
          deviations.evaluate_symmetric(states, mean, half, origin, predictions);
          double worst = 0, worst_whole = 0;
          for (Eigen::Index i = origin; i < states.cols(); ++i) {
            const Eigen::VectorXd truth = expected.col(i) - at_mean.col(0);
            const double size = truth.cwiseAbs().maxCoeff();
            worst = std::max(worst, (predictions.col(i) - expected.col(i)).cwiseAbs().maxCoeff() / size);
            worst_whole =
                std::max(worst_whole, (whole.col(i) - expected.col(i)).cwiseAbs().maxCoeff() / size);
          }
          for (Eigen::Index i = 0; i < origin; ++i)  // the mean itself: no deviation but rounding
            EXPECT_LT((predictions.col(i) - at_mean.col(0)).cwiseAbs().maxCoeff(), 1e-9);
          EXPECT_LT(worst, 2e-6) << s2kf::instruction_set_name(set) << ", deviations of " << scale;
          EXPECT_GT(worst, 0.0);  // it did run in float
          if (scale == 1e-5) {
            EXPECT_GT(worst_whole, 1e-3);  // the bound tells float deviations from float poses
          }
        }
      }
    }
  }
  s2kf::use_instruction_set(active);
}

TEST(MarkerMeasurementModel, SymmetricEvaluationIsTheOrdinaryOneWithoutFloatDeviations) {
  const BodyModel body = mmm_body_model(1690);
  MarkerMeasurementModel h(body, OrientationParameterization::local_rotation_error);
  std::mt19937 rng(12);
  const Eigen::VectorXd mean = random_states(rng, 1, 0.3).col(0);
  const Eigen::MatrixXd half = 0.1 * random_states(rng, 20, 0.3);
  const Eigen::MatrixXd states = symmetric_states(mean, half, 1);
  Eigen::MatrixXd expected(150, 41), predictions(150, 41);
  h(states, expected);
  h.evaluate_symmetric(states, mean, half, 1, predictions);
  EXPECT_EQ(predictions, expected);
  h.set_single_precision_deviations(true);
  EXPECT_THROW(h.evaluate_symmetric(states, mean, half.leftCols(19), 1, predictions), s2kf::DimensionError);
  EXPECT_THROW(h.evaluate_symmetric(states, mean.head(45), half, 1, predictions), s2kf::DimensionError);
  // After the first call with these sizes, no allocation.
  h.evaluate_symmetric(states, mean, half, 1, predictions);
  allocations = 0;
  counting = true;
  h.evaluate_symmetric(states, mean, half, 1, predictions);
  counting = false;
  EXPECT_EQ(allocations.load(), 0);
}

TEST(MarkerMeasurementModel, TheFiltersFloatDeviationsAreThoseOfEvaluateSymmetric) {
  // evaluate_symmetric_deviations hands the filter the float deviations that evaluate_symmetric
  // adds to the mean pose's predictions: the same numbers to the bit, for selected markers in any
  // order; markers_at (every marker at one state, which the tracker reports and then draws its
  // samples about) is the model's own evaluation there.
  const BodyModel body = mmm_body_model(1720);
  std::mt19937 rng(13);
  const Eigen::VectorXd mean = random_states(rng, 1, 0.3).col(0);
  const Eigen::MatrixXf half_f = (0.05 * random_states(rng, 20, 0.3)).cast<float>();
  const Eigen::MatrixXd half = half_f.cast<double>();
  const Eigen::MatrixXd states = symmetric_states(mean, half, 1);
  MarkerMeasurementModel h(body, OrientationParameterization::local_rotation_error), all(h);
  h.set_reference_orientation(rotation_from_rpy(Eigen::Vector3d(0.2, -0.4, 1.1)));
  all.set_reference_orientation(h.reference_orientation());
  h.select_markers({40, 3, 17, 0, 49});
  Eigen::MatrixXf deviations(15, 41);
  Eigen::VectorXd mean_prediction(15);
  EXPECT_FALSE(h.evaluate_symmetric_deviations(mean, half_f, 1, deviations, mean_prediction));  // off
  h.set_single_precision_deviations(true);
  Eigen::MatrixXd predictions(15, 41), at_mean(15, 1);
  h.evaluate_symmetric(states, mean, half, 1, predictions);
  ASSERT_TRUE(h.evaluate_symmetric_deviations(mean, half_f, 1, deviations, mean_prediction));
  EXPECT_EQ(Eigen::MatrixXd(deviations.cast<double>().colwise() + mean_prediction), predictions);
  h(mean, at_mean);
  EXPECT_LT((mean_prediction - at_mean.col(0)).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT(deviations.col(5).cwiseAbs().maxCoeff(), 1.0f);  // deviations of millimetres
  const Eigen::VectorXd markers = h.markers_at(mean);
  Eigen::MatrixXd every(150, 1);
  all(mean, every);
  EXPECT_EQ(markers, every.col(0));  // the same batched evaluation of every marker
  EXPECT_THROW(h.evaluate_symmetric_deviations(mean, half_f.leftCols(19), 1, deviations, mean_prediction),
               s2kf::DimensionError);
  EXPECT_THROW(h.evaluate_symmetric_deviations(mean, half_f, 1, deviations, mean_prediction.head(14)),
               s2kf::DimensionError);
  EXPECT_THROW(h.markers_at(mean.head(45)), s2kf::DimensionError);
  // A new reference orientation is a new pose, though the state is the same.
  h.set_reference_orientation(Eigen::Matrix3d::Identity());
  all.set_reference_orientation(Eigen::Matrix3d::Identity());
  all(mean, every);
  EXPECT_EQ(h.markers_at(mean), every.col(0));
}

// At pitch = 90 deg roll and yaw turn about the same axis: their marker Jacobian columns are parallel.
// The local rotation error keeps three independent directions there.
TEST(MarkerMeasurementModel, LocalRotationErrorStaysFullRankAtPitchNinetyDegrees) {
  const BodyModel body = mmm_body_model();
  auto orientation_jacobian = [&](MarkerMeasurementModel& h, const Eigen::VectorXd& x) {
    Eigen::MatrixXd states(kStateDimension, 6);
    for (int k = 0; k < 3; ++k) {
      states.col(2 * k) = x;
      states.col(2 * k + 1) = x;
      states(3 + k, 2 * k) += 1e-6;
      states(3 + k, 2 * k + 1) -= 1e-6;
    }
    Eigen::MatrixXd y(h.measurement_dimension(), 6);
    h(states, y);
    Eigen::MatrixXd jacobian(h.measurement_dimension(), 3);
    for (int k = 0; k < 3; ++k) jacobian.col(k) = (y.col(2 * k) - y.col(2 * k + 1)) / 2e-6;
    return jacobian;
  };
  Eigen::VectorXd x = Eigen::VectorXd::Zero(kStateDimension);
  x(4) = M_PI / 2;
  MarkerMeasurementModel rpy(body);
  const Eigen::JacobiSVD<Eigen::MatrixXd> rpy_svd(orientation_jacobian(rpy, x));
  EXPECT_LT(rpy_svd.singularValues()(2), 1e-6 * rpy_svd.singularValues()(0));

  MarkerMeasurementModel local(body, OrientationParameterization::local_rotation_error);
  local.set_reference_orientation(rotation_from_rpy(x.segment<3>(3)));
  x.segment<3>(3).setZero();
  const Eigen::JacobiSVD<Eigen::MatrixXd> local_svd(orientation_jacobian(local, x));
  EXPECT_GT(local_svd.singularValues()(2), 0.1 * local_svd.singularValues()(0));
}

TEST(MarkerMeasurementModel, RecenterKeepsThePredictionAndZeroesTheRotationError) {
  const BodyModel body = mmm_body_model();
  MarkerMeasurementModel h(body, OrientationParameterization::local_rotation_error);
  h.set_reference_orientation(rotation_from_rpy(Eigen::Vector3d(0.1, -M_PI / 2, 0.3)));
  std::mt19937 rng(3);
  Eigen::MatrixXd state = random_states(rng, 1, 0.3);
  Eigen::MatrixXd before(150, 1), after(150, 1);
  h(state, before);
  const Pose pose_before = h.pose(state.col(0));
  Eigen::VectorXd x = state.col(0);
  h.recenter(x);
  EXPECT_TRUE(x.segment<3>(3).isZero(0));
  state.col(0) = x;
  h(state, after);
  EXPECT_LT((before - after).cwiseAbs().maxCoeff(), 1e-9);
  // state(pose) inverts pose(state).
  const Eigen::VectorXd round_trip = h.state(pose_before);
  h(round_trip, after);
  EXPECT_LT((before - after).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(MarkerMeasurementModel, SelectedMarkersComeInTheRequestedOrder) {
  const BodyModel body = mmm_body_model();
  MarkerMeasurementModel all(body), some(body);
  const std::vector<int> chosen{body.marker_index("RTOE"), body.marker_index("C7"),
                                body.marker_index("LAOL")};
  some.select_markers(chosen);
  ASSERT_EQ(some.measurement_dimension(), 9);
  std::mt19937 rng(4);
  const Eigen::MatrixXd states = random_states(rng, 70, 1.0);
  Eigen::MatrixXd y_all(150, 70), y_some(9, 70);
  all(states, y_all);
  some(states, y_some);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(y_some.middleRows(3 * k, 3), y_all.middleRows(3 * chosen[k], 3));
  EXPECT_THROW(some.select_markers({0, 50}), std::invalid_argument);
  Eigen::MatrixXd wrong(10, 70);
  EXPECT_THROW(some(states, wrong), s2kf::DimensionError);
  EXPECT_THROW(some(Eigen::MatrixXd::Zero(45, 70), y_some), s2kf::DimensionError);
}

TEST(MarkerMeasurementModel, EveryKernelVariantGivesTheSamePredictionsAsOnePoseAtATime) {
  // The variants transpose the markers out of the block differently (4 x 4 tiles with AVX2 and
  // AVX-512, one number at a time with SSE2): counts of poses and rows that are not multiples of 4
  // reach every edge of the tiles.
  const BodyModel body = mmm_body_model(1690);
  MarkerMeasurementModel h(body, OrientationParameterization::local_rotation_error);
  const Eigen::Matrix3d reference = rotation_from_rpy(Eigen::Vector3d(-0.3, 1.2, 2.0));
  h.set_reference_orientation(reference);
  std::vector<int> chosen;
  for (const char* name : {"RTOE", "C7", "LAOL", "RHEE", "LFHD", "RWTS", "T10"})
    chosen.push_back(body.marker_index(name));
  h.select_markers(chosen);
  std::mt19937 rng(7);
  const Eigen::MatrixXd states = random_states(rng, 131, 0.5);
  const BoundedJoints bounded(body);
  const s2kf::InstructionSet active = s2kf::active_instruction_set();
  for (const auto set :
       {s2kf::InstructionSet::sse2, s2kf::InstructionSet::avx2, s2kf::InstructionSet::avx512}) {
    if (set > s2kf::supported_instruction_set() || set < s2kf::compiled_instruction_set()) continue;
    s2kf::use_instruction_set(set);
    Eigen::MatrixXd predictions(21, states.cols());
    h(states, predictions);
    for (Eigen::Index i = 0; i < states.cols(); ++i) {
      const Eigen::Matrix3Xd all = marker_positions(body, states.col(i).head<3>(),
                                                    reference * rotation_exp(states.col(i).segment<3>(3)),
                                                    bounded.angles(states.col(i).tail<kJointCount>()));
      for (int k = 0; k < 7; ++k)
        ASSERT_LT((predictions.col(i).segment<3>(3 * k) - all.col(chosen[k])).cwiseAbs().maxCoeff(), 1e-9)
            << s2kf::instruction_set_name(set) << ", pose " << i << ", marker " << k;
    }
  }
  s2kf::use_instruction_set(active);
}

TEST(MarkerMeasurementModel, NaNStatesGiveNaNPredictionsInTheirColumnOnly) {
  MarkerMeasurementModel h(mmm_body_model());
  std::mt19937 rng(6);
  Eigen::MatrixXd states = random_states(rng, 3, 1.0);
  states(20, 1) = std::numeric_limits<double>::quiet_NaN();
  Eigen::MatrixXd y(150, 3);
  h(states, y);
  EXPECT_TRUE(y.col(0).allFinite());
  EXPECT_FALSE(y.col(1).allFinite());
  EXPECT_TRUE(y.col(2).allFinite());
}

TEST(MarkerMeasurementModel, DoesNotAllocateAfterTheFirstCall) {
  MarkerMeasurementModel h(mmm_body_model(), OrientationParameterization::local_rotation_error);
  std::mt19937 rng(5);
  const Eigen::MatrixXd states = random_states(rng, 301, 1.0);
  Eigen::MatrixXd y(150, 301);
  h(states, y);
  allocations = 0;
  counting = true;
  { const std::vector<int> probe(10); }  // the counter itself must see allocations
  counting = false;
  ASSERT_EQ(allocations.load(), 1);
  allocations = 0;
  counting = true;
  h(states, y);
  h(states.leftCols(120), y.leftCols(120));
  counting = false;
  EXPECT_EQ(allocations.load(), 0);
}

TEST(MarkerNoise, IsDiagonalWithThreeEntriesPerMarker) {
  const Eigen::MatrixXd r = marker_noise(4.0, 50);
  ASSERT_EQ(r.rows(), 150);
  EXPECT_TRUE(r.isApprox(4.0 * Eigen::MatrixXd::Identity(150, 150)));
  const Eigen::MatrixXd per = marker_noise(Eigen::Vector2d(1.0, 9.0));
  Eigen::VectorXd expected(6);
  expected << 1, 1, 1, 9, 9, 9;
  EXPECT_EQ(per, Eigen::MatrixXd(expected.asDiagonal()));
  EXPECT_THROW(marker_noise(-1.0, 3), std::invalid_argument);
  EXPECT_THROW(marker_noise(Eigen::Vector2d(1.0, std::nan(""))), std::invalid_argument);
}

}  // namespace
