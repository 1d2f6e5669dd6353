// Forward kinematics of the 40-joint, 50-marker body model: single pose, batched blocks, Jacobian,
// and the tracker's measurement model. Counters report poses per second (items_per_second).
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_measurement_model.hpp>

#include <benchmark/benchmark.h>

#include <random>

namespace {

using namespace s2kf::body;

Eigen::MatrixXd random_states(Eigen::Index count) {
  std::mt19937 rng(42);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd states(kStateDimension, count);
  for (Eigen::Index i = 0; i < count; ++i)
    for (int k = 0; k < kStateDimension; ++k) states(k, i) = (k < 3 ? 500.0 : 1.0) * normal(rng);
  return states;
}

void BM_ForwardKinematicsSinglePose(benchmark::State& state) {
  const BodyModel model = mmm_body_model();
  Pose pose;
  pose.joints.setConstant(0.3);
  pose.root_rpy << 0.1, 0.2, 0.3;
  for (auto _ : state) {
    Eigen::Matrix3Xd markers = marker_positions(model, pose);
    benchmark::DoNotOptimize(markers.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ForwardKinematicsSinglePose);

void BM_ForwardKinematicsBatched(benchmark::State& state) {
  const Eigen::Index count = state.range(0);
  const BodyModel model = mmm_body_model();
  const Eigen::MatrixXd states = random_states(count);
  Eigen::MatrixXd rotations(9, count);
  for (Eigen::Index i = 0; i < count; ++i) {
    const Eigen::Matrix3d r = rotation_from_rpy(states.col(i).segment<3>(3));
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) rotations(3 * a + b, i) = r(a, b);
  }
  ForwardKinematicsWorkspace ws;
  Eigen::MatrixXd markers(3 * model.marker_count(), count);
  for (auto _ : state) {
    marker_positions_batch(model, states.topRows(3), rotations, states.bottomRows(kJointCount), ws, markers);
    benchmark::DoNotOptimize(markers.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * count);
}
BENCHMARK(BM_ForwardKinematicsBatched)->Arg(301)->Arg(461);

void BM_MarkerJacobian(benchmark::State& state) {
  const BodyModel model = mmm_body_model();
  Pose pose;
  pose.joints.setConstant(0.3);
  for (auto _ : state) {
    Eigen::MatrixXd jacobian = marker_jacobian(model, pose);
    benchmark::DoNotOptimize(jacobian.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_MarkerJacobian);

void BM_MarkerMeasurementModel(benchmark::State& state) {
  const Eigen::Index count = state.range(0);
  const auto orientation = static_cast<OrientationParameterization>(state.range(1));
  MarkerMeasurementModel h(mmm_body_model(), orientation);
  const Eigen::MatrixXd states = random_states(count);
  Eigen::MatrixXd predictions(h.measurement_dimension(), count);
  for (auto _ : state) {
    h(states, predictions);
    benchmark::DoNotOptimize(predictions.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * count);
}
BENCHMARK(BM_MarkerMeasurementModel)
    ->Args({301, static_cast<int>(OrientationParameterization::roll_pitch_yaw)})
    ->Args({301, static_cast<int>(OrientationParameterization::local_rotation_error)})
    ->Args({461, static_cast<int>(OrientationParameterization::roll_pitch_yaw)});

}  // namespace

BENCHMARK_MAIN();
