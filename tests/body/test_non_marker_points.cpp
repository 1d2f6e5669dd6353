// Points that are no markers, told by their labels: model outputs, joint centres, centres of mass
// and Plug-in Gait's segment axes are recognised; markers, cluster markers and a lone PELA are not.
#include <s2kf/body/non_marker_points.hpp>

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using s2kf::body::non_marker_reason;

TEST(NonMarkerPoints, RecognisesModelOutputsJointCentresAndCentresOfMass) {
  const std::vector<std::string> labels;
  const auto reason = [&](const std::string& label) { return non_marker_reason(label, labels).value_or(""); };
  EXPECT_NE(reason("LKneeAngles").find("joint angles"), std::string::npos);
  EXPECT_NE(reason("Subject:RHipAngles").find("joint angles"), std::string::npos);
  EXPECT_NE(reason("LAnkleForce").find("forces"), std::string::npos);
  EXPECT_NE(reason("RKneeMoment").find("moments"), std::string::npos);
  EXPECT_NE(reason("LHipPower").find("powers"), std::string::npos);
  EXPECT_NE(reason("LGroundReactionForce").find("forces"), std::string::npos);
  EXPECT_NE(reason("LNormalisedGRF").find("ground reaction"), std::string::npos);
  EXPECT_NE(reason("LHJC").find("joint centre"), std::string::npos);
  EXPECT_NE(reason("rkjc").find("joint centre"), std::string::npos);
  EXPECT_NE(reason("L_HJC").find("joint centre"), std::string::npos);
  EXPECT_NE(reason("V_R.Hip_JC").find("joint centre"), std::string::npos);
  EXPECT_NE(reason("V_Mid_ASIS").find("virtual point"), std::string::npos);
  EXPECT_NE(reason("R.Knee_JC").find("joint centre"), std::string::npos);
  EXPECT_NE(reason("CentreOfMass").find("centre of mass"), std::string::npos);
  EXPECT_NE(reason("CentreOfMassFloor").find("centre of mass"), std::string::npos);
  for (const char* marker : {"LASI", "LKNE", "C7", "T10", "RFIN", "LFMA", "PELA", "LGT", "Angle", "JC", ""})
    EXPECT_FALSE(non_marker_reason(marker, labels)) << marker;
}

TEST(NonMarkerPoints, SegmentAxesOnlyAsAQuartet) {
  const std::vector<std::string> axes{"PELO", "PELA", "PELL", "PELP", "LFEO", "LFEA", "LFEL"};
  for (const char* label : {"PELO", "PELA", "PELL", "PELP"})
    EXPECT_NE(non_marker_reason(label, axes).value_or("").find("segment axis"), std::string::npos) << label;
  EXPECT_FALSE(non_marker_reason("LFEO", axes));  // LFEP is missing: no quartet
  const std::vector<std::string> cluster{"PELA", "PELB", "PELC", "PELD"};
  for (const std::string& label : cluster) EXPECT_FALSE(non_marker_reason(label, cluster)) << label;
}

}  // namespace
