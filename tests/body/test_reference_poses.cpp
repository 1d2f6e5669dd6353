// The reference poses of a static trial: in the T-pose the wrists are level with the shoulders and
// out to the sides, in the A-pose half-way down, in the zero pose beside the hips; an unknown name
// is refused.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/reference_poses.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace {

using namespace s2kf;

/// Origins of the left shoulder's and the left wrist's frames in a pose of the named reference.
std::pair<Eigen::Vector3d, Eigen::Vector3d> left_shoulder_and_wrist(const std::string& name) {
  const body::BodyModel model = body::mmm_body_model(1750);
  const body::FrameTransforms frames = body::joint_frames(
      model, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), body::reference_pose(model, name));
  return {frames.origins[static_cast<std::size_t>(model.frame_index("LSx"))],
          frames.origins[static_cast<std::size_t>(model.frame_index("LWx"))]};
}

TEST(ReferencePoses, TheArmsPointWhereThePoseSays) {
  const auto [shoulder_zero, wrist_zero] = left_shoulder_and_wrist("zero");
  const double arm = (wrist_zero - shoulder_zero).norm();
  EXPECT_LT(wrist_zero.z(), shoulder_zero.z() - 0.9 * arm);  // hanging
  const auto [shoulder_t, wrist_t] = left_shoulder_and_wrist("t-pose");
  EXPECT_NEAR(wrist_t.z(), shoulder_t.z(), 0.1 * arm);  // level
  EXPECT_LT(wrist_t.x(), shoulder_t.x() - 0.9 * arm);   // out to the left (x is to the right)
  const auto [shoulder_a, wrist_a] = left_shoulder_and_wrist("a-pose");
  EXPECT_NEAR(shoulder_a.z() - wrist_a.z(), arm * std::sin(M_PI / 4), 0.1 * arm);
  const body::BodyModel model = body::mmm_body_model(1750);
  EXPECT_EQ(body::reference_pose(model, "zero").norm(), 0.0);
  EXPECT_THROW(body::reference_pose(model, "y-pose"), std::invalid_argument);
  for (const std::string& name : body::reference_pose_names()) {
    const Eigen::VectorXd pose = body::reference_pose(model, name);
    EXPECT_TRUE((pose.array() >= model.lower_limits().array()).all() &&
                (pose.array() <= model.upper_limits().array()).all())
        << name;
  }
}

}  // namespace
