// The BVH as Blender sees it: imported with Debian's blender in background mode at the importer's
// default settings (scale 1.0, -Z forward, Y up), every joint's world position at several frames
// must be the library's forward kinematics within 1 mm, and the scene's frame rate the recording's.
#include "motion_test_support.hpp"

#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/io/bvh.hpp>

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

namespace s2kf {
namespace {

using test_support::random_poses;
using test_support::read_text_file;
using test_support::scratch_directory;
using test_support::unevenly_scaled_model;

// Debian 12's blender 3.4 ships an importer that opens the file with mode 'rU', which Python 3.11
// removed; the script shadows `open` inside the importer module with one that drops the 'U'.
// It prints "FPS fps fps_base" and "P frame bone x y z" (world head positions, metres).
const char* const kImportScript = R"(import bpy, builtins, addon_utils, sys
addon_utils.enable('io_anim_bvh')
import io_anim_bvh.import_bvh as importer
importer.open = lambda path, mode='r', *a, **k: builtins.open(path, mode.replace('U', ''), *a, **k)
bvh, out, frames = sys.argv[sys.argv.index('--') + 1:]
bpy.ops.import_anim.bvh(filepath=bvh, update_scene_fps=True)
armature = bpy.context.active_object
scene = bpy.context.scene
with open(out, 'w') as f:
    f.write('FPS %r %r\n' % (scene.render.fps, scene.render.fps_base))
    for frame in range(1, int(frames) + 1):
        scene.frame_set(frame)
        for bone in armature.pose.bones:
            p = armature.matrix_world @ bone.head
            f.write('P %d %s %r %r %r\n' % (frame, bone.name, p.x, p.y, p.z))
)";

TEST(BvhInBlender, EveryJointIsWhereTheLibraryPutsItWithinAMillimetreAndTheFrameRateCarries) {
  if (std::system("blender --version > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "blender cannot run here (`blender --version` failed: not installed or not on PATH); "
                    "scripts/test.sh installs Debian's blender package";
  const std::string dir = scratch_directory("bvh_blender");
  const body::BodyModel model = unevenly_scaled_model();
  const double rate_hz = 120;
  const int frames = 5;
  const io::MotionTable motion = random_poses(model, frames, rate_hz, 18);
  io::save_bvh(dir + "/motion.bvh", model, motion, rate_hz);
  std::ofstream(dir + "/import.py") << kImportScript;
  const std::string command = "blender -b --factory-startup --python " + dir + "/import.py -- " + dir +
                              "/motion.bvh " + dir + "/joints.txt " + std::to_string(frames) + " > " + dir +
                              "/blender.log 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << read_text_file(dir + "/blender.log");

  std::istringstream lines(read_text_file(dir + "/joints.txt"));
  std::map<std::pair<int, std::string>, Eigen::Vector3d> blender_mm;
  double fps = 0, fps_base = 0;
  for (std::string tag; lines >> tag;) {
    if (tag == "FPS") {
      lines >> fps >> fps_base;
      continue;
    }
    ASSERT_EQ(tag, "P") << read_text_file(dir + "/blender.log");
    int frame = 0;
    std::string bone;
    Eigen::Vector3d p;
    lines >> frame >> bone >> p.x() >> p.y() >> p.z();
    blender_mm[{frame - 1, bone}] = 1000 * p;  // Blender's frames start at 1
  }
  EXPECT_NEAR(fps / fps_base, rate_hz, 1e-4);  // fps_base is a float32 in Blender

  // The library's joint centres: the root, and each group's frame (its first DoF carries the offset).
  double worst_mm = 0;
  int compared = 0;
  for (int r = 0; r < frames; ++r) {
    const Eigen::VectorXd row = motion.values.row(r).transpose();
    const body::FrameTransforms frames_of_pose = body::joint_frames(
        model, row.head<3>(), body::rotation_from_rpy(row.segment<3>(3)), row.tail(model.joint_count()));
    std::map<std::string, Eigen::Vector3d> expected{{"pelvis", frames_of_pose.origins[0]}};
    for (int j = 0; j < model.joint_count(); ++j)
      expected.emplace(model.joints[j].group, frames_of_pose.origins[j + 1]);  // first DoF of the group
    for (const auto& [group, centre] : expected) {
      const auto found = blender_mm.find({r, group});
      ASSERT_NE(found, blender_mm.end()) << "Blender has no bone " << group << " at frame " << r;
      const double error = (found->second - centre).norm();
      EXPECT_LT(error, 1.0) << group << " at frame " << r;
      worst_mm = std::max(worst_mm, error);
      ++compared;
    }
  }
  EXPECT_EQ(compared, frames * 17);  // the pelvis and 16 groups
  std::cout << "Blender vs forward kinematics: " << compared << " joint positions, worst " << worst_mm
            << " mm\n";
  RecordProperty("worst_joint_error_mm", std::to_string(worst_mm));
}

TEST(Bvh, CentimetreFilesAreTheMetreFilesTimesAHundred) {
  const body::BodyModel model = unevenly_scaled_model();
  const io::MotionTable motion = random_poses(model, 3, 100, 5);
  std::ostringstream metres, centimetres;
  io::write_bvh(metres, model, motion, 100, io::BvhUnits::metres);
  io::write_bvh(centimetres, model, motion, 100, io::BvhUnits::centimetres);
  // Offsets and root positions scale; angles do not.
  const std::regex offset(R"re(OFFSET (\S+) (\S+) (\S+))re");
  const std::string m = metres.str(), cm = centimetres.str();
  std::sregex_iterator a(m.begin(), m.end(), offset), b(cm.begin(), cm.end(), offset), end;
  int offsets = 0;
  for (; a != end && b != end; ++a, ++b, ++offsets)
    for (int k = 1; k <= 3; ++k) EXPECT_NEAR(100 * std::stod((*a)[k]), std::stod((*b)[k]), 1e-4);
  EXPECT_EQ(offsets, 1 + 16 + 5);  // root, groups, end sites (head, two hands, two feet)
  const auto first_row = [](const std::string& text) {
    std::istringstream in(text.substr(text.find('\n', text.find("Frame Time:")) + 1));
    std::vector<double> values(9);
    for (double& v : values) in >> v;
    return values;
  };
  const std::vector<double> row_m = first_row(m), row_cm = first_row(cm);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(100 * row_m[c], row_cm[c], 1e-4);
  EXPECT_NEAR(row_m[0], motion.values(0, 0) / 1000, 1e-6);  // x stays x, in metres
  EXPECT_NEAR(row_m[1], motion.values(0, 2) / 1000, 1e-6);  // BVH Y = model z (up)
  EXPECT_NEAR(row_m[2], -motion.values(0, 1) / 1000, 1e-6);
  for (int c = 3; c < 9; ++c) EXPECT_DOUBLE_EQ(row_m[c], row_cm[c]);
}

}  // namespace
}  // namespace s2kf
