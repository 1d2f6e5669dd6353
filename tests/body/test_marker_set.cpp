// Marker sets as data: parsing and validation, applying a set to the model, choosing the set that
// fits a recording, and the subject file `s2kf calibrate` writes.
#include <s2kf/app/marker_set_json.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/marker_set_mapping.hpp>
#include <s2kf/io/c3d_reader.hpp>

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

using namespace s2kf;
namespace fs = std::filesystem;

std::vector<std::string> labels_in_file(const std::string& file) {
  c3d::C3dReader reader(std::string(S2KF_C3D_DATA_DIR) + "/" + file);
  std::vector<std::string> labels;
  for (const auto& label : reader.info().labels)
    labels.push_back(label.model_output ? std::string() : label.raw);
  return labels;
}

std::string parse_error(const std::string& text) {
  try {
    const body::MarkerSet set = app::marker_set_from_json(nlohmann::json::parse(text), "test.json");
    body::apply_marker_set(body::mmm_body_model(1000), set);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(MarkerSet, ParsingAndValidationNameTheProblem) {
  EXPECT_NE(parse_error(R"({"markers": [{"label": "A", "frame": "XX", "offset": [0, 0, 0]}]})")
                .find("unknown frame 'XX'"),
            std::string::npos);
  EXPECT_NE(parse_error(R"({"markers": [{"label": "A", "like": "C7"}, {"label": "a", "like": "T10"}]})")
                .find("mapped twice"),
            std::string::npos);
  EXPECT_NE(
      parse_error(R"({"markers": [{"label": "A", "like": "NOPE"}]})").find("not a marker of the base model"),
      std::string::npos);
  EXPECT_NE(
      parse_error(R"({"markers": [{"label": "A", "frame": "LS", "offset": [0, 0]}]})").find("array of 3"),
      std::string::npos);
  EXPECT_NE(parse_error(R"({"markers": [{"label": "A", "frame": "LS"}]})").find("needs an \"offset\""),
            std::string::npos);
  EXPECT_NE(parse_error(R"({"markers": [{"label": "A", "frame": "LS", "offset": [0,0,0], "colour": 1}]})")
                .find("unknown key"),
            std::string::npos);
  EXPECT_NE(parse_error(R"({"markers": []})").find("has no markers"), std::string::npos);
  EXPECT_NE(parse_error(R"({"segment_scale": {"XX": 1.0}, "markers": [{"label": "A", "like": "C7"}]})")
                .find("unknown segment"),
            std::string::npos);
  EXPECT_EQ(parse_error(R"({"markers": [{"label": "A", "like": "C7", "noise_mm": 5, "weight": 2}]})"), "");
  // Joint limits: a known joint, two finite numbers, lower below upper, at most 2 pi apart.
  const auto limits_error = [](const std::string& limits) {
    return parse_error(R"({"joint_limits": )" + limits + R"(, "markers": [{"label": "A", "like": "C7"}]})");
  };
  EXPECT_NE(limits_error(R"({"XKx": [-1, 0]})").find("unknown joint 'XKx'"), std::string::npos);
  EXPECT_NE(limits_error(R"({"LKx": [0, -2.6]})").find("lower < upper"), std::string::npos);
  EXPECT_NE(limits_error(R"({"LKx": [-1, -1]})").find("lower < upper"), std::string::npos);
  EXPECT_NE(limits_error(R"({"LKx": [-4, 3]})").find("at most 2 pi apart"), std::string::npos);
  EXPECT_NE(limits_error(R"({"LKx": [-2.6]})").find("[lower, upper]"), std::string::npos);
  EXPECT_NE(limits_error(R"([-2.6, 0])").find("joint_limits must be an object"), std::string::npos);
  EXPECT_NE(limits_error(R"({"LKx": ["a", 0]})").find("joint_limits.LKx"), std::string::npos);
  EXPECT_EQ(limits_error(R"({"LKx": [-2.6, 0], "RKx": [-2.6, 0.1]})"), "");
}

// joint_limits replace the model's range of the named joints only, and travel through the JSON
// form and into the subject file s2kf calibrate writes.
TEST(MarkerSet, JointLimitsReplaceTheModelsRange) {
  body::MarkerSet set = app::resolve_marker_set("cmu");
  set.joint_limits["LKx"] = {-2.6, 0.0};
  set.joint_limits["RAy"] = {-0.6, 0.5};
  const body::BodyModel base = body::mmm_body_model(1750);
  const body::BodyModel model = body::apply_marker_set(base, set);
  for (int j = 0; j < base.joint_count(); ++j) {
    const std::string& name = base.joints[j].name;
    const double lower = name == "LKx" ? -2.6 : name == "RAy" ? -0.6 : base.joints[j].lower;
    const double upper = name == "LKx" ? 0.0 : name == "RAy" ? 0.5 : base.joints[j].upper;
    EXPECT_EQ(model.joints[j].lower, lower) << name;
    EXPECT_EQ(model.joints[j].upper, upper) << name;
  }
  EXPECT_NE(base.joints[base.joint_index("LKx")].lower, -2.6);  // the model's own range differs
  const body::MarkerSet again = app::marker_set_from_json(app::marker_set_to_json(set), "again");
  EXPECT_EQ(again.joint_limits, set.joint_limits);
  const body::MarkerSet subject = app::subject_marker_set(set, model.scaled(1750), {}, {}, "subject");
  EXPECT_EQ(subject.joint_limits, set.joint_limits);
  EXPECT_EQ(body::apply_marker_set(base, subject).joints[base.joint_index("LKx")].lower, -2.6);
}

TEST(MarkerSet, AppliedSetPutsMarkersWhereTheSetSays) {
  // An explicit offset in the LE frame at 1000 mm, applied to a 1800 mm model: FK must put the
  // marker at origin(LE) + R(LE) * offset * 1.8 in any pose.
  body::MarkerSet set;
  set.entries.push_back({"ELB", {}, "LE", std::nullopt, Eigen::Vector3d(10, -20, 30), std::nullopt, 1.0});
  set.entries.push_back({"ASIS", {}, "", std::string("LASI"), Eigen::Vector3d(0, 0, 5), std::nullopt, 1.0});
  const body::BodyModel base = body::mmm_body_model(1800);
  const body::BodyModel model = body::apply_marker_set(base, set);
  ASSERT_EQ(model.marker_count(), 2);
  body::Pose pose;
  pose.root_position = Eigen::Vector3d(100, 200, 900);
  pose.root_rpy = Eigen::Vector3d(0.1, -0.2, 0.7);
  for (int j = 0; j < base.joint_count(); ++j)
    pose.joints(j) = 0.5 * (base.joints[j].lower + base.joints[j].upper);
  const body::FrameTransforms frames = body::joint_frames(base, pose);
  const Eigen::Matrix3Xd markers = body::marker_positions(model, pose);
  const int le = base.frame_index("LE");
  const Eigen::Vector3d expected = frames.origins[le] + frames.rotations[le] * Eigen::Vector3d(18, -36, 54);
  EXPECT_LT((markers.col(0) - expected).norm(), 1e-9);
  // "like LASI" + 5 mm up the pelvis at 1000 mm = LASI of the base model + 9 mm along the root's z.
  const Eigen::Matrix3Xd base_markers = body::marker_positions(base, pose);
  const Eigen::Vector3d lasi = base_markers.col(base.marker_index("LASI"));
  EXPECT_LT((markers.col(1) - (lasi + frames.rotations[0] * Eigen::Vector3d(0, 0, 9))).norm(), 1e-9);
}

TEST(MarkerSet, KitSetReproducesTheModel) {
  const body::BodyModel base = body::mmm_body_model(1750);
  const body::BodyModel model = body::apply_marker_set(base, app::resolve_marker_set("kit"));
  ASSERT_EQ(model.marker_count(), base.marker_count());
  for (int m = 0; m < model.marker_count(); ++m) {
    EXPECT_EQ(model.markers[m].name, base.markers[m].name);
    EXPECT_EQ(model.markers[m].frame, base.markers[m].frame);
    // Bit for bit (the file holds 17 significant digits), so `s2kf track` with the chosen KIT set
    // tracks exactly as the library does with the model itself.
    EXPECT_EQ(model.markers[m].offset, base.markers[m].offset) << base.markers[m].name;
  }
  // The KIT set leaves no observed segment empty; only the shanks carry one marker (LTIP, RTIP).
  const std::vector<std::string> warnings = body::marker_set_warnings(base, model);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0].rfind("LK has 1 marker", 0), 0u);
  EXPECT_EQ(warnings[1].rfind("RK has 1 marker", 0), 0u);
}

TEST(MarkerSet, WarnsAboutSegmentsWithOneMarker) {
  const body::BodyModel base = body::mmm_body_model(1000);
  const std::vector<std::string> warnings =
      body::marker_set_warnings(base, body::apply_marker_set(base, app::resolve_marker_set("cmu")));
  bool lw = false;
  for (const auto& w : warnings) lw = lw || w.rfind("LW has 1 marker", 0) == 0;
  EXPECT_TRUE(lw);
}

TEST(MarkerSet, AutomaticChoiceFitsTheLab) {
  const std::vector<body::MarkerSet> sets{app::resolve_marker_set("kit"), app::resolve_marker_set("cmu"),
                                          app::resolve_marker_set("plugin_gait")};
  EXPECT_EQ(body::choose_marker_set(labels_in_file("85_02.c3d"), sets), 1);
  EXPECT_EQ(body::choose_marker_set(labels_in_file("HDM_mm_01-02_03_120.c3d"), sets), 1);
  EXPECT_EQ(body::choose_marker_set(labels_in_file("PiG_Motion-FlatFoot-One.c3d"), sets), 2);
  EXPECT_EQ(body::choose_marker_set(labels_in_file("test1.c3d"), sets), 2);
  EXPECT_EQ(body::choose_marker_set(sets[0].labels(), sets), 0);
  EXPECT_EQ(body::choose_marker_set({"foo", "bar"}, sets), -1);
  EXPECT_DOUBLE_EQ(body::marker_set_match(labels_in_file("85_02.c3d"), sets[1]), 1.0);
  // test1 labels the forearm LFRA: the alias maps it to LFRM.
  const body::MarkerMapping mapping = body::map_marker_set(labels_in_file("test1.c3d"), sets[2]);
  const std::vector<std::string> pig_labels = sets[2].labels();
  const auto lfrm = std::find(pig_labels.begin(), pig_labels.end(), "LFRM") - pig_labels.begin();
  ASSERT_GE(mapping.point_of_marker[static_cast<std::size_t>(lfrm)], 0);
  EXPECT_EQ(
      labels_in_file(
          "test1.c3d")[static_cast<std::size_t>(mapping.point_of_marker[static_cast<std::size_t>(lfrm)])],
      "LFRA");
}

TEST(MarkerSet, JsonRoundTrip) {
  const body::MarkerSet set = app::resolve_marker_set("plugin_gait");
  const body::MarkerSet again = app::marker_set_from_json(app::marker_set_to_json(set), "again");
  const body::BodyModel base = body::mmm_body_model(1000);
  const body::BodyModel a = body::apply_marker_set(base, set), b = body::apply_marker_set(base, again);
  for (int m = 0; m < a.marker_count(); ++m) EXPECT_EQ(a.markers[m].offset, b.markers[m].offset);
}

}  // namespace
