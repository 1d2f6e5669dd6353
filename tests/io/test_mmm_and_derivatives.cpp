// The MMM XML motion (well-formed, MMM's sensors, joint names and units, values that read back) and
// the finite-difference derivatives (against the analytic derivatives of a sinusoidal motion), and
// MotionStreamWriter writing both byte for byte as the batch writers do.
#include "motion_test_support.hpp"

#include <s2kf/io/mmm_motion.hpp>
#include <s2kf/io/motion_derivatives.hpp>
#include <s2kf/io/motion_stream_writer.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <regex>
#include <sstream>
#include <string>

namespace s2kf {
namespace {

using test_support::random_poses;
using test_support::read_text_file;
using test_support::scratch_directory;
using test_support::unevenly_scaled_model;

std::vector<double> numbers_of(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> values;
  for (double v; in >> v;) values.push_back(v);
  return values;
}

TEST(MmmMotion, IsWellFormedWithModelPoseAndKinematicSensorsThatReadBack) {
  const body::BodyModel model = unevenly_scaled_model();
  io::MotionTable motion = random_poses(model, 4, 100, 3);
  motion.values.row(2).setConstant(NAN);  // untracked: left out
  const std::string dir = scratch_directory("mmm");
  io::save_mmm_motion(dir + "/walk.xml", motion, "walk", model.height_mm);
  if (std::system("xmllint --version > /dev/null 2>&1") == 0)
    EXPECT_EQ(std::system(("xmllint --noout " + dir + "/walk.xml").c_str()), 0);
  else
    std::cout << "xmllint not installed: well-formedness not checked here\n";
  const std::string text = read_text_file(dir + "/walk.xml");
  EXPECT_NE(text.find("<MMM version=\"2.0\">"), std::string::npos);
  EXPECT_NE(text.find("<Height>1.75</Height>"), std::string::npos);  // metres
  EXPECT_NE(text.find("<Sensor type=\"ModelPose\" version=\"1.0\">"), std::string::npos);
  EXPECT_NE(text.find("<Sensor type=\"Kinematic\" version=\"1.0\">"), std::string::npos);
  std::vector<std::string> joints;
  const std::regex joint(R"re(<Joint name="([^"]+)" />)re");
  for (std::sregex_iterator it(text.begin(), text.end(), joint), end; it != end; ++it)
    joints.push_back((*it)[1]);
  ASSERT_EQ(joints.size(), 40u);
  EXPECT_EQ(joints.front(), "BPx_joint");
  EXPECT_EQ(joints.back(), "RAy_joint");

  const std::regex pose(
      R"re(<Measurement timestep="([^"]+)">\s*<RootPosition>([^<]+)</RootPosition>\s*<RootRotation>([^<]+)</RootRotation>)re");
  const std::regex angles(R"re(<Measurement timestep="([^"]+)">\s*<JointPosition>([^<]+)</JointPosition>)re");
  std::vector<Eigen::Index> rows{0, 1, 3};
  std::size_t k = 0;
  for (std::sregex_iterator it(text.begin(), text.end(), pose), end; it != end; ++it, ++k) {
    ASSERT_LT(k, rows.size());
    const Eigen::Index r = rows[k];
    EXPECT_NEAR(std::stod((*it)[1]), motion.time[static_cast<std::size_t>(r)], 1e-12);
    const std::vector<double> position = numbers_of((*it)[2]), rotation = numbers_of((*it)[3]);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(position[c], motion.values(r, c), 1e-5);      // mm
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(rotation[c], motion.values(r, 3 + c), 1e-8);  // rad
  }
  EXPECT_EQ(k, rows.size());
  k = 0;
  for (std::sregex_iterator it(text.begin(), text.end(), angles), end; it != end; ++it, ++k) {
    ASSERT_LT(k, rows.size());
    const std::vector<double> values = numbers_of((*it)[2]);
    ASSERT_EQ(values.size(), 40u);
    for (int j = 0; j < 40; ++j) EXPECT_NEAR(values[j], motion.values(rows[k], 6 + j), 1e-8);
  }
  EXPECT_EQ(k, rows.size());
}

// x(t) = A sin(w t + phase) per column: v = A w cos(.), a = -A w^2 sin(.). Three-point differences
// are off by O(h^2): |v error| <= A w^3 h^2 / 6, |a error| <= A w^4 h^2 / 12.
TEST(MotionDerivatives, MatchTheAnalyticDerivativesOfASinusoidalMotion) {
  const body::BodyModel model = body::mmm_body_model(1750);
  const double rate_hz = 200, h = 1 / rate_hz, omega = 2 * 3.14159265358979 * 1.5;
  const int frames = 60, columns = 6 + model.joint_count();
  io::MotionTable motion;
  motion.joint_names = model.joint_names();
  motion.values.resize(frames, columns);
  auto amplitude = [](int c) { return c < 3 ? 300.0 : 0.4 + 0.01 * c; };
  for (int r = 0; r < frames; ++r) {
    motion.frame.push_back(r);
    motion.time.push_back(r * h);
    for (int c = 0; c < columns; ++c) motion.values(r, c) = amplitude(c) * std::sin(omega * r * h + 0.1 * c);
  }
  // Yaw turning steadily through +-180 deg: the angle jumps by 2 pi, the rate does not.
  for (int r = 0; r < frames; ++r)
    motion.values(r, 5) = std::remainder(3.0 + 2.0 * r * h, 2 * 3.14159265358979);
  motion.values.row(30).setConstant(NAN);  // untracked: NaN there, one-sided next to it

  const auto [velocity, acceleration] = io::motion_derivatives(motion);
  for (int r = 0; r < frames; ++r) {
    const bool interior = r > 0 && r < frames - 1 && std::abs(r - 30) > 1;
    for (int c = 0; c < columns; ++c) {
      if (c == 5) continue;
      const double a = amplitude(c), phase = omega * r * h + 0.1 * c;
      if (r == 30) {
        EXPECT_TRUE(std::isnan(velocity.values(r, c)) && std::isnan(acceleration.values(r, c)));
      } else if (interior) {
        EXPECT_NEAR(velocity.values(r, c), a * omega * std::cos(phase),
                    a * std::pow(omega, 3) * h * h / 6 + 1e-9);
        EXPECT_NEAR(acceleration.values(r, c), -a * omega * omega * std::sin(phase),
                    a * std::pow(omega, 4) * h * h / 12 + 1e-6);
      } else {  // one-sided: first order, |error| <= A w^2 h / 2
        EXPECT_NEAR(velocity.values(r, c), a * omega * std::cos(phase), a * omega * omega * h / 2 + 1e-9);
        EXPECT_TRUE(std::isnan(acceleration.values(r, c)));
      }
    }
    if (r != 30) {
      EXPECT_NEAR(velocity.values(r, 5), 2.0, 1e-9) << r;
    }
    if (interior) {
      EXPECT_NEAR(acceleration.values(r, 5), 0.0, 1e-6) << r;
    }
  }
}

TEST(MotionStreamWriter, WritesTheMmmAndDerivativeFilesTheBatchWritersWriteWithItsCompanions) {
  const body::BodyModel model = unevenly_scaled_model();
  io::MotionTable motion = random_poses(model, 9, 120, 11);
  motion.values.row(0).setConstant(NAN);
  motion.values.row(4).setConstant(NAN);
  const std::string dir = scratch_directory("stream_mmm");
  io::save_mmm_motion(dir + "/batch.xml", motion, "walk", model.height_mm);
  const auto [velocity, acceleration] = io::motion_derivatives(motion);
  io::save_motion_csv(dir + "/batch_vel.csv", velocity);
  io::save_motion_csv(dir + "/batch_acc.csv", acceleration);
  io::MotionFilePaths paths;
  paths.mmm = dir + "/stream.xml";
  paths.velocity_csv = dir + "/stream_vel.csv";
  paths.acceleration_csv = dir + "/stream_acc.csv";
  {
    io::MotionStreamWriter abandoned(paths, model, 120, "walk");
    abandoned.companion(dir + "/stream.osim") << "model";
    abandoned.append(0, 0, motion.values.row(1).transpose());
  }  // destroyed without finish(): nothing stays
  EXPECT_FALSE(std::filesystem::exists(dir + "/stream.osim"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/stream.xml"));
  io::MotionStreamWriter writer(paths, model, 120, "walk");
  writer.companion(dir + "/stream.osim") << "model\n";
  for (Eigen::Index r = 0; r < motion.frames(); ++r)
    writer.append(motion.frame[r], motion.time[r], motion.values.row(r).transpose());
  EXPECT_FALSE(std::filesystem::exists(dir + "/stream.osim"));
  writer.finish();
  EXPECT_EQ(read_text_file(dir + "/stream.osim"), "model\n");
  EXPECT_TRUE(read_text_file(dir + "/stream.xml") == read_text_file(dir + "/batch.xml"));
  EXPECT_TRUE(read_text_file(dir + "/stream_vel.csv") == read_text_file(dir + "/batch_vel.csv"));
  EXPECT_TRUE(read_text_file(dir + "/stream_acc.csv") == read_text_file(dir + "/batch_acc.csv"));
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 7u);  // no temporaries left
}

}  // namespace
}  // namespace s2kf
