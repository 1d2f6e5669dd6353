// The MMM-style body model tables and the zero pose.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/pose_columns.hpp>

#include <gtest/gtest.h>

#include <stdexcept>

namespace {

using s2kf::body::BodyModel;
using s2kf::body::mmm_body_model;

TEST(BodyModel, HasFortyJointsAndFiftyMarkersInSpecOrder) {
  const BodyModel model = mmm_body_model();
  ASSERT_EQ(model.joint_count(), 40);
  ASSERT_EQ(model.marker_count(), 50);
  EXPECT_EQ(model.joints.front().name, "BPx");
  EXPECT_EQ(model.joints[29].name, "LKx");
  EXPECT_EQ(model.joints.back().name, "RAy");
  EXPECT_EQ(model.markers.front().name, "C7");
  EXPECT_EQ(model.markers.back().name, "RTOE");
  EXPECT_EQ(model.joint_index("RSy"), 21);
  EXPECT_EQ(model.joint_index("nope"), -1);
  EXPECT_EQ(model.marker_index("LTIP"), 38);
  EXPECT_EQ(model.marker_index("LIFD"), -1);
  EXPECT_NO_THROW(model.validate());
}

TEST(BodyModel, ParentsComeBeforeChildrenAndGroupsChainWithoutTranslation) {
  const BodyModel model = mmm_body_model(1000);
  for (int j = 0; j < model.joint_count(); ++j) EXPECT_LE(model.joints[j].parent_frame, j);
  // BTx hangs from the frame after BPy, 60 mm above the BP centre; BTz and BTy chain on.
  const int btx = model.joint_index("BTx");
  EXPECT_EQ(model.joints[btx].parent_frame, model.joint_index("BPy") + 1);
  EXPECT_TRUE(model.joints[btx].translation.isApprox(Eigen::Vector3d(0, 0, 60)));
  EXPECT_EQ(model.joints[btx + 1].parent_frame, btx + 1);
  EXPECT_TRUE(model.joints[btx + 1].translation.isZero(0));
  // Shoulders hang from the thorax: LS centre (-110, 0, 288) minus BT centre (0, 0, 100).
  const int lsx = model.joint_index("LSx");
  EXPECT_EQ(model.joints[lsx].parent_frame, model.frame_index("BT"));
  EXPECT_TRUE(model.joints[lsx].translation.isApprox(Eigen::Vector3d(-110, 0, 188)));
  EXPECT_EQ(model.joints[model.joint_index("LHx")].parent_frame, 0);
  EXPECT_EQ(model.frame_index("root"), 0);
  EXPECT_EQ(model.frame_index("LEx"), model.joint_index("LEx") + 1);
  EXPECT_EQ(model.frame_index("LE"), model.joint_index("LEz") + 1);
  EXPECT_EQ(model.frame_index("XX"), -1);
  // LAOL rides on the frame after elbow flexion only; LFRA on the whole elbow.
  EXPECT_EQ(model.markers[model.marker_index("LAOL")].frame, model.joint_index("LEx") + 1);
  EXPECT_EQ(model.markers[model.marker_index("LFRA")].frame, model.joint_index("LEz") + 1);
  EXPECT_DOUBLE_EQ(model.joints[model.joint_index("LSx")].upper, 3.31613);
  EXPECT_DOUBLE_EQ(model.joints[model.joint_index("RSy")].lower, -2.79253);
}

TEST(BodyModel, ZeroPosePutsEveryMarkerAtItsTablePositionTimesHeight) {
  for (double height : {1000.0, 1750.0, 1623.5}) {
    const BodyModel model = mmm_body_model(height);
    const Eigen::Matrix3Xd markers = s2kf::body::marker_positions(model, s2kf::body::Pose{});
    const double scale = height / 1000;
    for (int m = 0; m < model.marker_count(); ++m) {
      const auto& row = s2kf::body::mmm::kMarkerTable[m];
      EXPECT_NEAR(markers(0, m), row.x * scale, 1e-9) << row.name;
      EXPECT_NEAR(markers(1, m), row.y * scale, 1e-9) << row.name;
      EXPECT_NEAR(markers(2, m), row.z * scale, 1e-9) << row.name;
    }
    // Spot values typed from the spec independently of the table.
    const int c7 = model.marker_index("C7"), rhps = model.marker_index("RHPS"),
              ltoe = model.marker_index("LTOE");
    EXPECT_NEAR(markers(2, c7), 309.312 * scale, 1e-9);
    EXPECT_NEAR(markers(2, rhps), -84.243 * scale, 1e-9);
    EXPECT_NEAR(markers(1, ltoe), 113.750 * scale, 1e-9);
  }
}

TEST(BodyModel, ScaledMultipliesEveryLengthAndRejectsBadHeights) {
  const BodyModel small = mmm_body_model(1000);
  const BodyModel tall = small.scaled(2000);
  EXPECT_DOUBLE_EQ(tall.height_mm, 2000);
  for (int j = 0; j < small.joint_count(); ++j)
    EXPECT_TRUE(tall.joints[j].translation.isApprox(2 * small.joints[j].translation, 1e-15));
  for (int m = 0; m < small.marker_count(); ++m)
    EXPECT_TRUE(tall.markers[m].offset.isApprox(2 * small.markers[m].offset, 1e-15));
  EXPECT_THROW(small.scaled(0), std::invalid_argument);
  EXPECT_THROW(small.scaled(-5), std::invalid_argument);
  EXPECT_THROW(small.scaled(std::nan("")), std::invalid_argument);
}

TEST(BodyModel, MarkersCanBeAddedAndReplaced) {
  BodyModel model = mmm_body_model(1000);
  model.set_marker({"LFWT", 0, Eigen::Vector3d(-60, 40, 30)});
  EXPECT_EQ(model.marker_count(), 51);
  model.set_marker({"LASI", 0, Eigen::Vector3d(1, 2, 3)});
  EXPECT_EQ(model.marker_count(), 51);
  const Eigen::Matrix3Xd markers = s2kf::body::marker_positions(model, s2kf::body::Pose{});
  EXPECT_TRUE(markers.col(model.marker_index("LASI")).isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE(markers.col(50).isApprox(Eigen::Vector3d(-60, 40, 30)));
}

TEST(BodyModel, ValidateNamesTheBrokenRule) {
  BodyModel model = mmm_body_model(1000);
  model.joints[5].parent_frame = 10;
  EXPECT_THROW(model.validate(), std::invalid_argument);
  model = mmm_body_model(1000);
  model.markers[0].frame = 99;
  EXPECT_THROW(model.validate(), std::invalid_argument);
  model = mmm_body_model(1000);
  model.joints[0].lower = 1;
  EXPECT_THROW(model.validate(), std::invalid_argument);
}

TEST(PoseColumns, AreFrameTimeRootThenTheFortyJoints) {
  const auto columns = s2kf::body::pose_column_names();
  ASSERT_EQ(columns.size(), 48u);
  EXPECT_EQ(columns[0], "frame");
  EXPECT_EQ(columns[7], "root_yaw");
  EXPECT_EQ(columns[8], "BPx");
  EXPECT_EQ(columns[47], "RAy");
  EXPECT_EQ(s2kf::body::pose_column_names(mmm_body_model()), columns);
}

}  // namespace
