// Whether a marker set describes a whole body: the regions its markers ride on, by the model's
// kinematic tree; a head-and-neck set does not, a lower-body or an upper-body set does.
#include <s2kf/app/marker_set_json.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/markerset/body_coverage.hpp>

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using namespace s2kf;

TEST(BodyCoverage, RegionsFollowTheKinematicTree) {
  const body::BodyModel base = body::mmm_body_model(1000);
  EXPECT_EQ(markerset::body_region(base, "root"), "trunk");
  EXPECT_EQ(markerset::body_region(base, "BT"), "trunk");
  EXPECT_EQ(markerset::body_region(base, "BUN"), "head");
  EXPECT_EQ(markerset::body_region(base, "LW"), "left arm");
  EXPECT_EQ(markerset::body_region(base, "RE"), "right arm");
  EXPECT_EQ(markerset::body_region(base, "LA"), "left leg");
  EXPECT_EQ(markerset::body_region(base, "RK"), "right leg");
  EXPECT_EQ(markerset::covered_regions(base).size(), 6u);
}

TEST(BodyCoverage, PartialSetsOfABodyPassAHeadDoesNot) {
  const body::BodyModel base = body::mmm_body_model(1000);
  for (const char* name : {"plugin_gait", "plugin_gait_lower", "plugin_gait_upper", "cmu"})
    EXPECT_EQ(markerset::whole_body_problem(body::apply_marker_set(base, app::resolve_marker_set(name))), "")
        << name;
  body::MarkerSet face;
  face.name = "face";
  for (int k = 0; k < 12; ++k) {
    body::MarkerSetEntry entry;
    entry.label = "F" + std::to_string(k);
    entry.frame = k < 10 ? "BUN" : "BT";
    entry.offset = Eigen::Vector3d(10.0 * (k - 6), 80, k < 10 ? 400.0 + 5 * k : 300.0);
    face.entries.push_back(entry);
  }
  const std::string problem = markerset::whole_body_problem(body::apply_marker_set(base, face));
  EXPECT_NE(problem.find("does not look like a whole body"), std::string::npos) << problem;
  EXPECT_NE(problem.find("only the head and trunk"), std::string::npos) << problem;
  // Markers spanning 300 mm of a 1300 mm body: no whole body, whatever segments they were put on.
  const body::BodyModel whole = body::apply_marker_set(base, app::resolve_marker_set("plugin_gait"));
  const std::string small = markerset::whole_body_problem(whole, 300, 1300);
  EXPECT_NE(small.find("span 300 mm, 23 % of the 1300 mm body"), std::string::npos) << small;
  EXPECT_EQ(markerset::whole_body_problem(whole, 900, 1750), "");
}

}  // namespace
