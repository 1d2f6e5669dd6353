// The OpenSim files: the .osim is well-formed XML (xmllint), its coordinates are the .mot columns
// with the joint limits as ranges, and an independent reading of it (tests/io/osim_forward_kinematics.py,
// OpenSim's joint rules in plain Python) puts every marker where the library's forward kinematics
// does, turned into OpenSim's ground frame; the .trc follows OpenSim's marker file layout.
#include "motion_test_support.hpp"

#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/io/opensim_model.hpp>
#include <s2kf/io/trc_file.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace s2kf {
namespace {

using test_support::random_poses;
using test_support::read_text_file;
using test_support::scratch_directory;
using test_support::unevenly_scaled_model;

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> cells_of(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, '\t')) cells.push_back(cell);
  if (!line.empty() && line.back() == '\t') cells.emplace_back();
  return cells;
}

TEST(OpenSimModel, IsWellFormedXmlWithTheMotColumnsAsCoordinatesAndTheLimitsAsRanges) {
  if (std::system("xmllint --version > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "xmllint cannot run here (Debian package libxml2-utils; scripts/test.sh installs it)";
  const std::string dir = scratch_directory("osim_wellformed");
  const body::BodyModel model = unevenly_scaled_model();
  io::save_opensim_model(dir + "/subject.osim", model, "subject", {"LASI", "RKNE", "LAOL", "C7"});
  ASSERT_EQ(std::system(("xmllint --noout " + dir + "/subject.osim").c_str()), 0);
  const std::string text = read_text_file(dir + "/subject.osim");

  // Coordinates: the .mot columns after time, in order, with ranges and clamping.
  const std::regex coordinate(
      R"re(<Coordinate name="([^"]+)">\s*<default_value>(\S+)</default_value>\s*<default_speed_value>0</default_speed_value>\s*<range>(\S+) (\S+)</range>\s*<clamped>(\w+)</clamped>)re");
  std::vector<std::string> names;
  for (std::sregex_iterator it(text.begin(), text.end(), coordinate), end; it != end; ++it) {
    const std::smatch& m = *it;
    names.push_back(m[1]);
    const int joint = model.joint_index(m[1].str());
    if (joint < 0) continue;
    EXPECT_DOUBLE_EQ(std::stod(m[3]), model.joints[joint].lower) << m[1];
    EXPECT_DOUBLE_EQ(std::stod(m[4]), model.joints[joint].upper) << m[1];
    EXPECT_EQ(m[5], "true") << m[1];
    EXPECT_EQ(std::stod(m[2]), 0.0) << m[1];  // the zero pose
  }
  std::vector<std::string> mot_columns = io::motion_columns(model.joint_names());
  mot_columns.erase(mot_columns.begin(), mot_columns.begin() + 2);  // frame, time
  EXPECT_EQ(names, mot_columns);
  EXPECT_NE(text.find("<length_units>meters</length_units>"), std::string::npos);
  EXPECT_NE(text.find("<OpenSimDocument Version=\"40000\">"), std::string::npos);

  // The markers asked for, and only those.
  std::set<std::string> markers;
  const std::regex marker(R"re(<Marker name="([^"]+)">)re");
  for (std::sregex_iterator it(text.begin(), text.end(), marker), end; it != end; ++it)
    markers.insert((*it)[1]);
  EXPECT_EQ(markers, (std::set<std::string>{"C7", "LAOL", "LASI", "RKNE"}));
  EXPECT_THROW(io::save_opensim_model(dir + "/bad.osim", model, "bad", {"NOPE"}), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad.osim"));
}

TEST(OpenSimModel, AnIndependentReadingPutsEveryMarkerWhereForwardKinematicsDoes) {
  if (std::system("python3 --version > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "python3 cannot run here; the .osim's independent reading is a Python script";
  const std::string dir = scratch_directory("osim_kinematics");
  const body::BodyModel model = unevenly_scaled_model();
  io::save_opensim_model(dir + "/subject.osim", model, "subject");
  const io::MotionTable motion = random_poses(model, 4, 100, 7);
  // Coordinates as OpenSim holds them after reading the .mot: metres and radians.
  std::ofstream poses(dir + "/poses.txt");
  poses << std::setprecision(17);
  const std::vector<std::string> columns = io::motion_columns(model.joint_names());
  for (Eigen::Index r = 0; r < motion.frames(); ++r) {
    for (Eigen::Index c = 0; c < motion.values.cols(); ++c)
      poses << columns[static_cast<std::size_t>(c + 2)] << "=" << motion.values(r, c) * (c < 3 ? 1e-3 : 1.0)
            << " ";
    poses << "\n";
  }
  poses.close();
  const std::string script = std::string(S2KF_TEST_SOURCE_DIR) + "/io/osim_forward_kinematics.py";
  ASSERT_EQ(std::system(("python3 " + script + " " + dir + "/subject.osim " + dir + "/poses.txt > " + dir +
                         "/markers.txt 2> " + dir + "/python.log")
                            .c_str()),
            0)
      << read_text_file(dir + "/python.log");
  std::istringstream in(read_text_file(dir + "/markers.txt"));
  const Eigen::Matrix3d ground_from_lab = io::opensim_ground_from_lab();
  double worst_mm = 0;
  int compared = 0;
  for (int pose; in >> pose;) {
    std::string name;
    Eigen::Vector3d ground_m;
    in >> name >> ground_m.x() >> ground_m.y() >> ground_m.z();
    const Eigen::VectorXd row = motion.values.row(pose).transpose();
    const Eigen::Matrix3Xd lab = body::marker_positions(
        model, row.head<3>(), body::rotation_from_rpy(row.segment<3>(3)), row.tail(model.joint_count()));
    const Eigen::Vector3d expected_m = ground_from_lab * lab.col(model.marker_index(name)) / 1000.0;
    const double error_mm = 1000 * (ground_m - expected_m).norm();
    EXPECT_LT(error_mm, 1e-6) << name << " in pose " << pose;
    worst_mm = std::max(worst_mm, error_mm);
    ++compared;
  }
  EXPECT_EQ(compared, 4 * model.marker_count());
  std::cout << "OpenSim model vs forward kinematics: " << compared << " marker positions, worst " << worst_mm
            << " mm\n";
  // The ground rotation is the one the .osim declares: lab up is OpenSim's +Y, lab forward its +X.
  EXPECT_TRUE((ground_from_lab * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_TRUE((ground_from_lab * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitX()));
  const Eigen::Vector3d euler = io::opensim_ground_from_lab_xyz_euler();
  const Eigen::Matrix3d from_euler = body::axis_rotation(body::Axis::x, euler.x()) *
                                     body::axis_rotation(body::Axis::y, euler.y()) *
                                     body::axis_rotation(body::Axis::z, euler.z());
  EXPECT_TRUE(from_euler.isApprox(ground_from_lab, 1e-12));
}

TEST(OpenSimModel, DefaultPoseStandsOnTheFloor) {
  const body::BodyModel model = body::mmm_body_model(1800);
  std::ostringstream out;
  io::write_opensim_model(out, model, "standing");
  const std::regex root_z(R"re(<Coordinate name="root_z">\s*<default_value>(\S+)</default_value>)re");
  std::smatch m;
  const std::string text = out.str();
  ASSERT_TRUE(std::regex_search(text, m, root_z));
  // The sole is 530 mm below the root per 1000 mm of height; the lowest markers (heel) sit a little
  // lower: 516.5 of the model table's 1000.
  EXPECT_NEAR(std::stod(m[1]), 0.5165 * 1.8, 1e-9);
}

TEST(Trc, FollowsOpenSimsLayoutInItsGroundFrameWithEmptyCellsForMissingMarkers) {
  std::ostringstream out;
  io::write_trc_header(out, "walk.trc", 100, 2, {"LASI", "RASI"});
  Eigen::Matrix3Xd frame(3, 2);
  frame << 10, 40, 20, 50, 30, 60;
  io::write_trc_row(out, 1, 0.0, frame);
  frame.col(1).setConstant(NAN);
  io::write_trc_row(out, 2, 0.01, frame);
  const std::vector<std::string> lines = lines_of(out.str());
  ASSERT_EQ(lines.size(), 8u);
  EXPECT_EQ(lines[0], "PathFileType\t4\t(X/Y/Z)\twalk.trc");
  EXPECT_EQ(cells_of(lines[1]),
            (std::vector<std::string>{"DataRate", "CameraRate", "NumFrames", "NumMarkers", "Units",
                                      "OrigDataRate", "OrigDataStartFrame", "OrigNumFrames"}));
  EXPECT_EQ(cells_of(lines[2]), (std::vector<std::string>{"100", "100", "2", "2", "mm", "100", "1", "2"}));
  EXPECT_EQ(cells_of(lines[3]), (std::vector<std::string>{"Frame#", "Time", "LASI", "", "", "RASI", "", ""}));
  EXPECT_EQ(cells_of(lines[4]), (std::vector<std::string>{"", "", "X1", "Y1", "Z1", "X2", "Y2", "Z2"}));
  EXPECT_EQ(lines[5], "");
  // Lab (x right, y forward, z up) -> OpenSim ground (X forward, Y up, Z right).
  EXPECT_EQ(cells_of(lines[6]), (std::vector<std::string>{"1", "0", "20", "30", "10", "50", "60", "40"}));
  EXPECT_EQ(cells_of(lines[7]), (std::vector<std::string>{"2", "0.01", "20", "30", "10", "", "", ""}));
}

}  // namespace
}  // namespace s2kf
