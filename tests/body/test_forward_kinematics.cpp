// Forward kinematics: hand-computed poses, rigid root motion, batched = single, Jacobian = finite
// differences.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/pose.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <string>

namespace {

using namespace s2kf::body;

Eigen::Matrix3d rx(double a) {
  Eigen::Matrix3d r;
  r << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  return r;
}
Eigen::Matrix3d ry(double a) {
  Eigen::Matrix3d r;
  r << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  return r;
}
Eigen::Matrix3d rz(double a) {
  Eigen::Matrix3d r;
  r << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return r;
}

Eigen::Vector3d table_position(const std::string& name, double scale) {
  for (const auto& row : mmm::kMarkerTable)
    if (row.name == name) return scale * Eigen::Vector3d(row.x, row.y, row.z);
  throw std::logic_error("no marker " + name);
}

Pose random_pose(std::mt19937& rng, double joint_spread = 1.0) {
  std::uniform_real_distribution<double> unit(-1, 1);
  const BodyModel model = mmm_body_model();
  Pose pose;
  pose.root_position = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 1000;
  pose.root_rpy = Eigen::Vector3d(unit(rng) * 3, unit(rng) * 1.5, unit(rng) * 3);
  for (int j = 0; j < kJointCount; ++j) {
    const double mid = 0.5 * (model.joints[j].lower + model.joints[j].upper);
    const double half = 0.5 * (model.joints[j].upper - model.joints[j].lower);
    pose.joints(j) = mid + joint_spread * half * unit(rng);
  }
  return pose;
}

TEST(ForwardKinematics, KneeFlexionSwingsExactlyTheShankAndFootMarkersAboutTheKnee) {
  const double height = 1750, scale = height / 1000;
  const BodyModel model = mmm_body_model(height);
  Pose pose;
  pose.joints(model.joint_index("LKx")) = -M_PI / 2;
  const Eigen::Matrix3Xd markers = marker_positions(model, pose);
  const Eigen::Vector3d knee = scale * Eigen::Vector3d(-52, 0, -245);
  // Rx(-pi/2) by hand: (x, y, z) -> (x, z, -y) about the knee centre.
  const std::set<std::string> moved{"LTIP", "LANK", "LHEE", "LMT1", "LMT5", "LTOE"};
  for (int m = 0; m < model.marker_count(); ++m) {
    const std::string& name = model.markers[m].name;
    const Eigen::Vector3d zero = table_position(name, scale);
    Eigen::Vector3d expected = zero;
    if (moved.count(name)) {
      const Eigen::Vector3d d = zero - knee;
      expected = knee + Eigen::Vector3d(d.x(), d.z(), -d.y());
    }
    EXPECT_NEAR((markers.col(m) - expected).norm(), 0, 1e-9) << name;
  }
  // The ankle marker ends up behind the knee (negative y) at knee height: flexion bends backwards.
  const Eigen::Vector3d lank = markers.col(model.marker_index("LANK"));
  EXPECT_LT(lank.y(), knee.y() - 400);
  EXPECT_NEAR(lank.z(), knee.z(), 1);
}

TEST(ForwardKinematics, ThreeDofGroupComposesXThenZThenY) {
  const double scale = 1.0;
  const BodyModel model = mmm_body_model(1000);
  const double a = 0.7, b = -0.4, c = 1.1;
  Pose pose;
  pose.joints(model.joint_index("LSx")) = a;
  pose.joints(model.joint_index("LSz")) = b;
  pose.joints(model.joint_index("LSy")) = c;
  const Eigen::Matrix3Xd markers = marker_positions(model, pose);
  const Eigen::Vector3d shoulder(-110, 0, 288);
  for (const char* name : {"LUPA", "LAEL", "LAOL", "LFRA", "LHTS"}) {
    const Eigen::Vector3d zero = table_position(name, scale);
    const Eigen::Vector3d expected = shoulder + rx(a) * rz(b) * ry(c) * (zero - shoulder);
    const Eigen::Vector3d other_order = shoulder + rx(a) * ry(c) * rz(b) * (zero - shoulder);
    const Eigen::Vector3d actual = markers.col(model.marker_index(name));
    EXPECT_NEAR((actual - expected).norm(), 0, 1e-9) << name;
    EXPECT_GT((actual - other_order).norm(), 1.0) << name << ": the test must tell the orders apart";
  }
  EXPECT_NEAR((markers.col(model.marker_index("RUPA")) - table_position("RUPA", scale)).norm(), 0, 1e-12);
}

TEST(ForwardKinematics, ElbowAxialRotationLeavesTheFlexionFrameMarkerAlone) {
  const BodyModel model = mmm_body_model(1000);
  Pose pose;
  pose.joints(model.joint_index("LEx")) = 1.2;
  pose.joints(model.joint_index("LEz")) = 0.8;
  const Eigen::Matrix3Xd markers = marker_positions(model, pose);
  const Eigen::Vector3d elbow(-110, 0, 100);
  const Eigen::Vector3d laol = elbow + rx(1.2) * (table_position("LAOL", 1) - elbow);
  const Eigen::Vector3d lfra = elbow + rx(1.2) * rz(0.8) * (table_position("LFRA", 1) - elbow);
  EXPECT_NEAR((markers.col(model.marker_index("LAOL")) - laol).norm(), 0, 1e-9);
  EXPECT_NEAR((markers.col(model.marker_index("LFRA")) - lfra).norm(), 0, 1e-9);
}

TEST(ForwardKinematics, RootPoseMovesEveryMarkerRigidly) {
  std::mt19937 rng(3);
  const BodyModel model = mmm_body_model();
  Pose pose = random_pose(rng);
  const Eigen::Matrix3Xd local =
      marker_positions(model, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), pose.joints);
  const Eigen::Matrix3Xd world = marker_positions(model, pose);
  const Eigen::Matrix3d r = rz(pose.root_rpy(2)) * ry(pose.root_rpy(1)) * rx(pose.root_rpy(0));
  for (int m = 0; m < model.marker_count(); ++m)
    EXPECT_NEAR((world.col(m) - (r * local.col(m) + pose.root_position)).norm(), 0, 1e-9);
}

TEST(ForwardKinematics, JointFramesGiveSegmentOrientations) {
  const BodyModel model = mmm_body_model(1000);
  Pose pose;
  pose.joints(model.joint_index("BPx")) = 0.3;
  pose.joints(model.joint_index("BTx")) = 0.2;
  const FrameTransforms frames = joint_frames(model, pose);
  ASSERT_EQ(frames.rotations.size(), 41u);
  const int thorax = model.frame_index("BT");
  EXPECT_TRUE(frames.rotations[thorax].isApprox(rx(0.5), 1e-14));
  EXPECT_TRUE(frames.origins[thorax].isApprox(Eigen::Vector3d(0, 0, 40) + rx(0.3) * Eigen::Vector3d(0, 0, 60),
                                              1e-14));
}

TEST(RollPitchYaw, RoundTripsIncludingGimbalLock) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int k = 0; k < 200; ++k) {
    Eigen::Vector3d rpy(unit(rng) * 3, unit(rng) * 1.5, unit(rng) * 3);
    if (k % 4 == 1) rpy(1) = M_PI / 2;
    if (k % 4 == 2) rpy(1) = -M_PI / 2;
    const Eigen::Matrix3d r = rotation_from_rpy(rpy);
    EXPECT_TRUE(r.isApprox(rz(rpy(2)) * ry(rpy(1)) * rx(rpy(0)), 1e-14));
    const Eigen::Vector3d back = rpy_from_rotation(r);
    EXPECT_LT((rotation_from_rpy(back) - r).norm(), 1e-11) << rpy.transpose();
    if (k % 4 == 0) {
      EXPECT_LT((back - rpy).norm(), 1e-9);
    }
  }
}

TEST(RotationVector, ExpAndLogAreInverse) {
  const Eigen::Vector3d v(0.3, -1.2, 2.0);
  EXPECT_TRUE(rotation_log(rotation_exp(v)).isApprox(v, 1e-12));
  EXPECT_TRUE(rotation_exp(Eigen::Vector3d::Zero()).isIdentity(0));
  EXPECT_TRUE(rotation_exp(Eigen::Vector3d(0, 0, 0.5)).isApprox(rz(0.5), 1e-14));
}

void check_batch_equals_single(Eigen::Index count, unsigned seed) {
  std::mt19937 rng(seed);
  const BodyModel model = mmm_body_model(1680);
  Eigen::MatrixXd positions(3, count), rotations(9, count), angles(kJointCount, count);
  std::vector<Pose> poses;
  for (Eigen::Index i = 0; i < count; ++i) {
    // Angles beyond the limits and far out of [-pi, pi] too: FK itself does not clamp.
    Pose pose = random_pose(rng, i % 5 == 4 ? 40.0 : 1.5);
    if (i % 7 == 3) pose.root_rpy(1) = M_PI / 2;
    positions.col(i) = pose.root_position;
    const Eigen::Matrix3d r = pose.root_rotation();
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) rotations(3 * a + b, i) = r(a, b);
    angles.col(i) = pose.joints;
    poses.push_back(pose);
  }
  ForwardKinematicsWorkspace ws;
  Eigen::MatrixXd markers(3 * model.marker_count(), count);
  marker_positions_batch(model, positions, rotations, angles, ws, markers);
  double worst = 0;
  for (Eigen::Index i = 0; i < count; ++i) {
    const Eigen::Matrix3Xd single = marker_positions(model, poses[i]);
    const Eigen::Map<const Eigen::VectorXd> stacked(single.data(), single.size());
    worst = std::max(worst, (markers.col(i) - stacked).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-12 * 1000) << "L = " << count;  // 1e-12 relative to metre-sized coordinates
  EXPECT_LT(worst, 1e-9) << "L = " << count;
}

TEST(BatchedForwardKinematics, EqualsSinglePoseForwardKinematics) {
  check_batch_equals_single(1, 1);
  check_batch_equals_single(7, 2);
  check_batch_equals_single(301, 3);
  check_batch_equals_single(1001, 4);  // four blocks
}

TEST(BatchedForwardKinematics, WorksOnBlocksOfAStateMatrixAndReusesTheWorkspace) {
  std::mt19937 rng(9);
  const BodyModel model = mmm_body_model();
  const Eigen::Index count = 130;
  Eigen::MatrixXd states(3 + 9 + kJointCount, count);
  for (Eigen::Index i = 0; i < count; ++i) {
    const Pose pose = random_pose(rng);
    const Eigen::Matrix3d r = pose.root_rotation();
    states.col(i).head<3>() = pose.root_position;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) states(3 + 3 * a + b, i) = r(a, b);
    states.col(i).tail<kJointCount>() = pose.joints;
  }
  ForwardKinematicsWorkspace ws;
  Eigen::MatrixXd out(2 + 3 * model.marker_count(), count);
  marker_positions_batch(model, states.topRows(3), states.middleRows(3, 9), states.bottomRows(kJointCount),
                         ws, out.bottomRows(3 * model.marker_count()));
  const Eigen::MatrixXd first = out.bottomRows(3 * model.marker_count());
  marker_positions_batch(model, states.topRows(3), states.middleRows(3, 9), states.bottomRows(kJointCount),
                         ws, out.bottomRows(3 * model.marker_count()));
  EXPECT_EQ(first, out.bottomRows(3 * model.marker_count()));
  Pose pose;
  pose.root_position = states.col(77).head<3>();
  pose.root_rpy =
      rpy_from_rotation(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(&states(3, 77)));
  pose.joints = states.col(77).tail<kJointCount>();
  const Eigen::Matrix3Xd single = marker_positions(model, pose);
  EXPECT_LT(
      (first.col(77) - Eigen::Map<const Eigen::VectorXd>(single.data(), single.size())).cwiseAbs().maxCoeff(),
      1e-9);
}

TEST(BatchedForwardKinematics, RejectsMismatchedSizes) {
  const BodyModel model = mmm_body_model();
  ForwardKinematicsWorkspace ws;
  Eigen::MatrixXd markers(3 * model.marker_count(), 4);
  EXPECT_THROW(marker_positions_batch(model, Eigen::MatrixXd::Zero(3, 4), Eigen::MatrixXd::Zero(9, 4),
                                      Eigen::MatrixXd::Zero(39, 4), ws, markers),
               s2kf::DimensionError);
  EXPECT_THROW(marker_positions_batch(model, Eigen::MatrixXd::Zero(3, 4), Eigen::MatrixXd::Zero(9, 3),
                                      Eigen::MatrixXd::Zero(40, 4), ws, markers),
               s2kf::DimensionError);
  EXPECT_THROW(
      marker_positions(model, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), Eigen::VectorXd::Zero(3)),
      s2kf::DimensionError);
}

TEST(MarkerJacobian, MatchesCentralDifferences) {
  std::mt19937 rng(11);
  const BodyModel model = mmm_body_model();
  for (int trial = 0; trial < 3; ++trial) {
    const Pose pose = random_pose(rng);
    const Eigen::MatrixXd jacobian = marker_jacobian(model, pose);
    ASSERT_EQ(jacobian.rows(), 150);
    ASSERT_EQ(jacobian.cols(), 46);
    auto stacked = [&](const Pose& p) {
      const Eigen::Matrix3Xd m = marker_positions(model, p);
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(m.data(), m.size()));
    };
    Eigen::MatrixXd numeric(150, 46);
    for (int k = 0; k < 46; ++k) {
      const double h = k < 3 ? 1e-3 : 1e-6;
      Pose plus = pose, minus = pose;
      if (k < 3) {
        plus.root_position(k) += h;
        minus.root_position(k) -= h;
      } else if (k < 6) {
        plus.root_rpy(k - 3) += h;
        minus.root_rpy(k - 3) -= h;
      } else {
        plus.joints(k - 6) += h;
        minus.joints(k - 6) -= h;
      }
      numeric.col(k) = (stacked(plus) - stacked(minus)) / (2 * h);
    }
    const double scale = jacobian.cwiseAbs().maxCoeff();
    EXPECT_LT((jacobian - numeric).cwiseAbs().maxCoeff(), 1e-6 * scale) << "trial " << trial;
    // Structure: a joint moves only markers downstream of it (LKx never moves the right foot).
    EXPECT_TRUE(jacobian.block(3 * model.marker_index("RANK"), 6 + model.joint_index("LKx"), 3, 1).isZero(0));
  }
}

}  // namespace

// A pose is sized by its model: one with a joint too many is refused, never read past its end.
TEST(ForwardKinematics, RefusesAPoseSizedForAnotherModel) {
  const s2kf::body::BodyModel model = s2kf::body::mmm_body_model(1750);
  const s2kf::body::Pose pose = s2kf::body::zero_pose(model);
  EXPECT_EQ(pose.joints.size(), model.joint_count());
  EXPECT_NO_THROW(s2kf::body::marker_positions(model, pose));
  const s2kf::body::Pose too_many{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                  Eigen::VectorXd::Zero(model.joint_count() + 1)};
  EXPECT_THROW(s2kf::body::marker_positions(model, too_many), s2kf::DimensionError);
  EXPECT_EQ(s2kf::body::pose_from_row(s2kf::body::pose_row(s2kf::body::zero_pose(model))).joints.size(),
            model.joint_count());
}
