// de Leva's segment inertia on the body model: the masses add up, each centre of mass lies on its
// segment at the table's fraction, the moments follow the table's radii of gyration, and the
// segments end at the model's joint centres.
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/segment_inertia.hpp>

#include <gtest/gtest.h>

#include <map>
#include <stdexcept>
#include <string>

namespace {

using s2kf::body::SegmentInertia;

std::map<std::string, SegmentInertia> by_segment(const std::vector<SegmentInertia>& segments) {
  std::map<std::string, SegmentInertia> map;
  for (const SegmentInertia& s : segments) map.emplace(s.segment, s);
  return map;
}

TEST(SegmentInertia, MassesAddUpToTheBodyMassInDeLevasProportions) {
  const s2kf::body::BodyModel model = s2kf::body::mmm_body_model(1800);
  const auto segments = by_segment(s2kf::body::de_leva_segment_inertia(model, 80.0));
  ASSERT_EQ(segments.size(), 16u);
  double total = 0;
  for (const auto& [name, s] : segments) total += s.mass_kg;
  EXPECT_NEAR(total, 80.0, 1e-9);
  EXPECT_NEAR(segments.at("LH").mass_kg, 0.1416 * 80, 1e-12);   // thigh
  EXPECT_NEAR(segments.at("RA").mass_kg, 0.0137 * 80, 1e-12);   // foot
  EXPECT_NEAR(segments.at("BUN").mass_kg, 0.0694 * 80, 1e-12);  // head and neck
  EXPECT_EQ(segments.count("BLN"), 0u);
}

TEST(SegmentInertia, TheThighRunsFromHipToKneeWithTheTablesCentreAndRadii) {
  const s2kf::body::BodyModel model = s2kf::body::mmm_body_model(1800);
  const auto segments = by_segment(s2kf::body::de_leva_segment_inertia(model, 80.0));
  const SegmentInertia& thigh = segments.at("LH");
  // In the thigh's frame (origin at the hip centre): the knee is the LK joint's translation.
  const Eigen::Vector3d knee = model.joints[static_cast<std::size_t>(model.joint_index("LKx"))].translation;
  EXPECT_TRUE(thigh.proximal_mm.isZero(1e-9));
  EXPECT_TRUE(thigh.distal_mm.isApprox(knee, 1e-12));
  EXPECT_TRUE(thigh.centre_of_mass_mm.isApprox(0.4095 * knee, 1e-12));
  const double length_m = knee.norm() / 1000;
  const double mass = 0.1416 * 80;
  EXPECT_NEAR(thigh.moments_kg_m2.x(), mass * std::pow(0.329 * length_m, 2), 1e-12);
  EXPECT_NEAR(thigh.moments_kg_m2.y(), mass * std::pow(0.329 * length_m, 2), 1e-12);
  EXPECT_NEAR(thigh.moments_kg_m2.z(), mass * std::pow(0.149 * length_m, 2), 1e-12);
  // The foot points forward: its smallest moment is about the antero-posterior axis (y).
  const SegmentInertia& foot = segments.at("LA");
  EXPECT_GT(foot.distal_mm.y(), foot.proximal_mm.y());
  EXPECT_LT(foot.moments_kg_m2.y(), foot.moments_kg_m2.x());
  EXPECT_LT(foot.moments_kg_m2.y(), foot.moments_kg_m2.z());
}

TEST(SegmentInertia, TheTrunkSpansHipsToNeckAndTheDefaultMassIsDeLevasBodyMassIndex) {
  const s2kf::body::BodyModel model = s2kf::body::mmm_body_model(1741);
  const auto segments = by_segment(s2kf::body::de_leva_segment_inertia(model, 73.0));
  // Pelvis (lower trunk) ends at the hips' midpoint (the root's origin), the upper trunk starts at
  // the lower neck joint: in the root frame, lower trunk + middle + upper span the root->BLN offset.
  const s2kf::body::FrameTransforms zero =
      s2kf::body::joint_frames(model, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(),
                               Eigen::VectorXd::Zero(model.joint_count()));
  const Eigen::Vector3d neck = zero.origins[static_cast<std::size_t>(model.frame_index("BLNx"))];
  const Eigen::Vector3d bt = zero.origins[static_cast<std::size_t>(model.frame_index("BT"))];
  EXPECT_TRUE(segments.at("root").distal_mm.isZero(1e-9));
  EXPECT_TRUE((segments.at("BT").proximal_mm + bt).isApprox(neck, 1e-12));
  EXPECT_NEAR(s2kf::body::default_body_mass_kg(1741), 73.0, 1e-12);
  EXPECT_NEAR(s2kf::body::default_body_mass_kg(2 * 1741), 4 * 73.0, 1e-9);
  EXPECT_THROW(s2kf::body::de_leva_segment_inertia(model, 0.0), std::invalid_argument);
  EXPECT_THROW(s2kf::body::de_leva_segment_inertia(model, -5.0), std::invalid_argument);
}

}  // namespace
