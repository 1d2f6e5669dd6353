// `s2kf calibrate`: writes a subject file that loads as a marker set and is taken back as
// --markerset, and names an unknown set.
#include "../../examples/s2kf/marker_set_json.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>

#include "address_sanitizer.hpp"
#include "cli_runner.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace {

using namespace s2kf;
namespace fs = std::filesystem;

TEST(CalibrateCommand, WritesASubjectFileThatLoads) {
  S2KF_SKIP_UNDER_SANITIZERS();
  const fs::path dir = fs::path(S2KF_TEST_TMP_DIR) / "marker_set";
  fs::create_directories(dir);
  const std::string recording = std::string(S2KF_C3D_DATA_DIR) + "/85_02.c3d";
  const std::string subject = (dir / "subject.json").string();
  const auto [status, output] =
      test_support::run_command("calibrate " + recording + " --frames 150 --iterations 1 --out " + subject);
  ASSERT_EQ(status, 0) << output;
  EXPECT_NE(output.find("marker set cmu"), std::string::npos) << output;
  const body::MarkerSet set = cli::load_marker_set(subject);
  ASSERT_TRUE(set.height_mm.has_value());
  EXPECT_EQ(set.entries.size(), 41u);
  const body::BodyModel model =
      body::apply_marker_set(body::mmm_body_model(1000), set).scaled(*set.height_mm);
  EXPECT_EQ(model.marker_count(), 41);
  // And the CLI takes it back as --markerset.
  const auto [again, again_output] =
      test_support::run_command("calibrate " + recording + " --frames 150 --iterations 1 --markerset " +
                                subject + " --out " + (dir / "again.json").string());
  EXPECT_EQ(again, 0) << again_output;
  EXPECT_NE(again_output.find("from the marker-set file"), std::string::npos) << again_output;
  const auto [bad, bad_output] =
      test_support::run_command("calibrate " + recording + " --markerset nope --out x.json");
  EXPECT_EQ(bad, 1);
  EXPECT_NE(bad_output.find("unknown marker set 'nope'"), std::string::npos) << bad_output;
}

}  // namespace
