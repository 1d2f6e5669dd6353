// `s2kf markerset infer`: a set inferred for a recording with scrambled labels, written, used by
// `s2kf track` when no bundled set fits, found again by `s2kf view`; one rigid object is refused and
// nothing is written.
#include <s2kf/app/marker_set_json.hpp>

#include <s2kf/body/marker_set.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/c3d_writer.hpp>

#include "address_sanitizer.hpp"
#include "cli_runner.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "test_files.hpp"

namespace {

using namespace s2kf;
using test_support::data_file;

TEST(MarkersetCommand, InfersWritesTracksAndViews) {
  S2KF_SKIP_UNDER_SANITIZERS();
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(s2kf::test_support::tmp_dir()) / "inference";
  fs::create_directories(dir);
  const MarkerSequence walk = c3d::read_c3d(data_file("walk.c3d")).frames(0, 300);
  std::vector<std::string> labels;
  for (std::size_t i = 0; i < walk.labels.size(); ++i) labels.push_back("m" + std::to_string(100 + i));
  const std::string recording = (dir / "scrambled.c3d").string();
  c3d::write_c3d(recording, labels, walk.rate_hz, walk.positions, walk.visible);

  const std::string set_file = (dir / "inferred.json").string();
  const auto [status, output] =
      test_support::run_command("markerset infer " + recording + " --out " + set_file);
  ASSERT_EQ(status, 0) << output;
  EXPECT_NE(output.find("confidence"), std::string::npos) << output;
  const body::MarkerSet set = app::load_marker_set(set_file);
  EXPECT_EQ(set.entries.size(), labels.size());
  EXPECT_NE(set.description.find("Inferred"), std::string::npos);

  const std::string prefix = (dir / "tracked").string();
  const auto [tracked, track_output] =
      test_support::run_command("track " + recording + " --out " + prefix + " --samples 101 --formats csv");
  ASSERT_EQ(tracked, 0) << track_output;
  EXPECT_NE(track_output.find("inferred from the recording"), std::string::npos) << track_output;
  EXPECT_TRUE(fs::exists(prefix + "_markerset.json"));
  std::ifstream summary_file(prefix + ".json");
  const nlohmann::json summary = nlohmann::json::parse(summary_file);
  EXPECT_NE(summary["marker_set_source"].get<std::string>().find(prefix + "_markerset.json"),
            std::string::npos);

  // s2kf view rebuilds the session from the summary: it finds the inferred set beside the outputs.
  const auto [viewed, view_output] = test_support::run_command("view " + prefix);
  EXPECT_EQ(viewed, 0) << view_output;

  // One rigid object: refused, and nothing written.
  MarkerSequence rigid = walk;
  for (Eigen::Index f = 0; f < rigid.frame_count(); ++f)
    rigid.frame(f) = walk.frame(0).colwise() + Eigen::Vector3d(static_cast<double>(f), 0, 0);
  const std::string rigid_file = (dir / "rigid.c3d").string();
  c3d::write_c3d(rigid_file, labels, rigid.rate_hz, rigid.positions, rigid.visible);
  const std::string refused_set = (dir / "refused.json").string();
  const auto [refused, refused_output] =
      test_support::run_command("markerset infer " + rigid_file + " --out " + refused_set);
  EXPECT_EQ(refused, 1) << refused_output;
  EXPECT_NE(refused_output.find("no marker set can be inferred: all"), std::string::npos) << refused_output;
  EXPECT_FALSE(fs::exists(refused_set));
}

}  // namespace
