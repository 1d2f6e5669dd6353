#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/core/instruction_set.hpp>
#include <s2kf/core/product_tiles.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/sample_cache.hpp>
#include <s2kf/track/tracker.hpp>

#include <gtest/gtest.h>

#include <array>
#include <random>
#include <string>
#include <vector>

namespace {

using s2kf::InstructionSet;

// Every variant this processor and this build run, from the compiled baseline up.
std::vector<InstructionSet> runnable_sets() {
  std::vector<InstructionSet> sets;
  for (int s = static_cast<int>(s2kf::compiled_instruction_set());
       s <= static_cast<int>(s2kf::supported_instruction_set()); ++s)
    sets.push_back(static_cast<InstructionSet>(s));
  return sets;
}

// Puts back the variant the process started with when a test ends.
struct RestoreInstructionSet {
  InstructionSet before = s2kf::active_instruction_set();
  ~RestoreInstructionSet() { s2kf::use_instruction_set(before); }
};

}  // namespace

TEST(InstructionSet, ChoosesTheBestSupportedUnlessForcedAndRejectsWhatCannotRun) {
  EXPECT_EQ(s2kf::choose_instruction_set(nullptr), s2kf::supported_instruction_set());
  EXPECT_EQ(s2kf::choose_instruction_set(""), s2kf::supported_instruction_set());
  EXPECT_GE(s2kf::supported_instruction_set(), s2kf::compiled_instruction_set());
  for (InstructionSet set : runnable_sets())
    EXPECT_EQ(s2kf::choose_instruction_set(s2kf::instruction_set_name(set)), set);
  try {
    s2kf::choose_instruction_set("avx1024");
    FAIL() << "an unknown variant was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("S2KF_SIMD=avx1024 is not a kernel variant"), std::string::npos);
  }
  for (int s = static_cast<int>(s2kf::supported_instruction_set()) + 1; s <= 2; ++s)
    EXPECT_THROW(s2kf::use_instruction_set(static_cast<InstructionSet>(s)), std::invalid_argument);
}

// Each variant's tiles against the product in double (each float product rounded once, so they
// agree to the float epsilon times the sum of the terms' magnitudes), at the tracker's sizes and at
// sizes that leave partial tiles.
TEST(InstructionSet, EveryVariantsProductTilesAgreeWithTheProductInDouble) {
  std::mt19937 random(7);
  std::normal_distribution<float> normal(0.0f, 10.0f);
  for (const auto& [rows, columns, samples] :
       std::vector<std::array<Eigen::Index, 3>>{{150, 46, 301}, {150, 150, 150}, {37, 13, 5}, {3, 2, 7}}) {
    const Eigen::MatrixXf a = Eigen::MatrixXf::NullaryExpr(rows, samples, [&] { return normal(random); });
    const Eigen::MatrixXf b = Eigen::MatrixXf::NullaryExpr(columns, samples, [&] { return normal(random); });
    const Eigen::MatrixXd exact = a.cast<double>() * b.cast<double>().transpose();
    const Eigen::MatrixXd magnitude = a.cast<double>().cwiseAbs() * b.cast<double>().cwiseAbs().transpose();
    const Eigen::MatrixXd exact_self = a.cast<double>() * a.cast<double>().transpose();
    for (InstructionSet set : runnable_sets()) {
      SCOPED_TRACE(s2kf::instruction_set_name(set));
      Eigen::MatrixXf c = Eigen::MatrixXf::Zero(rows, columns);
      s2kf::product_tiles_detail::add_products({a.data(), a.outerStride()}, {b.data(), b.outerStride()},
                                               samples, c.data(), c.outerStride(), rows, columns, false, set);
      EXPECT_LE(((c.cast<double>() - exact).cwiseAbs() - 4e-7 * magnitude).maxCoeff(), 0.0);
      Eigen::MatrixXf self = Eigen::MatrixXf::Constant(rows, rows, 7.0f);
      self.triangularView<Eigen::Lower>().setZero();
      s2kf::product_tiles_detail::add_products({a.data(), a.outerStride()}, {a.data(), a.outerStride()},
                                               samples, self.data(), self.outerStride(), rows, rows, true,
                                               set);
      const Eigen::MatrixXd lower = self.cast<double>().triangularView<Eigen::Lower>();
      const Eigen::MatrixXd lower_exact = exact_self.triangularView<Eigen::Lower>();
      EXPECT_LE((lower - lower_exact).cwiseAbs().maxCoeff(), 4e-7 * (a.cast<double>().cwiseAbs2().sum()));
      EXPECT_TRUE(
          (self.triangularView<Eigen::StrictlyUpper>().toDenseMatrix().array() ==
           Eigen::MatrixXf(Eigen::MatrixXf::Constant(rows, rows, 7.0f).triangularView<Eigen::StrictlyUpper>())
               .array())
              .all())
          << "a lower product wrote above the diagonal";
    }
  }
}

// The tracker's poses over the first 120 frames of the bundled handstand with every variant this
// machine runs (the kernels' sums run in the same order in every variant).
TEST(InstructionSet, TrackingGivesTheSamePosesWithEveryVariant) {
  const RestoreInstructionSet restore;
  const s2kf::c3d::Recording recording = s2kf::c3d::read_c3d(std::string(S2KF_DATA_DIR) + "/handstand.c3d");
  std::vector<std::string> labels;
  for (const auto& label : recording.info.labels) labels.push_back(label.name);
  const s2kf::body::BodyModel model = s2kf::body::mmm_body_model(1705);
  const s2kf::track::TrackerOptions options;
  const s2kf::SampleSet& samples = s2kf::lcd_sample_set(46, options.samples).set;
  const Eigen::Index frames = std::min<Eigen::Index>(120, recording.frame_count());
  std::vector<Eigen::MatrixXd> poses;  // per variant: 6 + 40 rows, one column per frame
  for (InstructionSet set : runnable_sets()) {
    s2kf::use_instruction_set(set);
    s2kf::track::Tracker tracker(model, s2kf::body::map_markers(labels, model.marker_names()), options,
                                 recording.info.rate, samples);
    Eigen::MatrixXd pose(6 + model.joint_count(), frames);
    for (Eigen::Index f = 0; f < frames; ++f) {
      const s2kf::track::FrameEstimate& e = tracker.process(recording.frame(f), recording.visible.col(f));
      ASSERT_TRUE(e.tracked) << "frame " << f;
      pose.col(f) << e.pose.root_position, e.pose.root_rpy, e.pose.joints;
    }
    poses.push_back(pose);
  }
  // The variants sum in the same order but round differently where they fuse multiply-adds (and
  // this file, compiled at -O1, adds its own copy of the inline kernels): in one process the poses
  // agree to 4e-6 rad and 4e-5 mm over 120 frames (measured), far below what tracking resolves; a
  // wrong kernel is off by orders of magnitude more. (The program's files are identical with avx2
  // and avx512, docs/benchmarks.md.)
  const std::vector<InstructionSet> sets = runnable_sets();
  for (std::size_t v = 0; v + 1 < poses.size(); ++v) {
    SCOPED_TRACE(std::string(s2kf::instruction_set_name(sets[v])) + " against " +
                 s2kf::instruction_set_name(sets.back()));
    EXPECT_LE((poses[v].bottomRows(43) - poses.back().bottomRows(43)).cwiseAbs().maxCoeff(), 1e-5) << "rad";
    EXPECT_LE((poses[v].topRows(3) - poses.back().topRows(3)).cwiseAbs().maxCoeff(), 1e-3) << "mm";
  }
}
