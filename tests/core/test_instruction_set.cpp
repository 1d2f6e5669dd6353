#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/core/bordered_cholesky.hpp>
#include <s2kf/core/instruction_set.hpp>
#include <s2kf/core/product_tiles.hpp>
#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/sample_cache.hpp>
#include <s2kf/track/tracker.hpp>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
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

// The double-precision tiles (the filter's rank updates, its sample draw S Z, the bordered
// Cholesky factorisation) of each variant against Eigen's products. A sum of k products, each
// rounded (or fused) once and added in some order, is within k u sum |a_t b_t| of the exact value
// (u = 2^-53, Higham's gamma_k); Eigen's and the tiles' may differ by twice that. Fused variants
// (AVX2, AVX-512) add the same terms in the same order, so they agree to the last bit.
TEST(InstructionSet, EveryVariantsDoubleTilesAgreeWithEigenAndFusedVariantsToTheBit) {
  const RestoreInstructionSet restore;
  const double u = std::numeric_limits<double>::epsilon() / 2;
  std::mt19937 random(11);
  std::normal_distribution<double> normal(0.0, 3.0);
  for (const auto& [rows, columns, samples] :
       std::vector<std::array<Eigen::Index, 3>>{{46, 150, 46}, {46, 46, 150}, {93, 31, 40}, {5, 3, 2}}) {
    const Eigen::MatrixXd a = Eigen::MatrixXd::NullaryExpr(rows, samples, [&] { return normal(random); });
    const Eigen::MatrixXd b = Eigen::MatrixXd::NullaryExpr(columns, samples, [&] { return normal(random); });
    // A lower triangular left operand (zeros above its diagonal, as the tiles require), rows x rows.
    const Eigen::MatrixXd l = Eigen::MatrixXd(Eigen::MatrixXd::NullaryExpr(rows, rows, [&] {
                                                return normal(random);
                                              }).triangularView<Eigen::Lower>());
    const Eigen::MatrixXd z = Eigen::MatrixXd::NullaryExpr(columns, rows, [&] { return normal(random); });
    const Eigen::MatrixXd c0 = Eigen::MatrixXd::NullaryExpr(rows, columns, [&] { return normal(random); });
    const Eigen::MatrixXd s0 = Eigen::MatrixXd::NullaryExpr(rows, rows, [&] { return normal(random); });
    const auto bound = [u](const Eigen::MatrixXd& magnitude, Eigen::Index k) {
      return Eigen::MatrixXd(2 * (k + 1) * u * magnitude);
    };
    const Eigen::MatrixXd product = c0 + a * b.transpose();
    const Eigen::MatrixXd product_bound =
        bound(c0.cwiseAbs() + a.cwiseAbs() * b.cwiseAbs().transpose(), samples);
    Eigen::MatrixXd down = s0;
    down.selfadjointView<Eigen::Lower>().rankUpdate(a, -1.0);
    const Eigen::MatrixXd down_bound =
        bound(s0.cwiseAbs() + a.cwiseAbs() * a.cwiseAbs().transpose(), samples);
    const Eigen::MatrixXd triangular = c0 + l.triangularView<Eigen::Lower>() * z.transpose();
    const Eigen::MatrixXd triangular_bound =
        bound(c0.cwiseAbs() + l.cwiseAbs() * z.cwiseAbs().transpose(), rows);
    std::vector<std::array<Eigen::MatrixXd, 3>> results;
    for (InstructionSet set : runnable_sets()) {
      SCOPED_TRACE(std::string(s2kf::instruction_set_name(set)) + ", " + std::to_string(rows) + " x " +
                   std::to_string(columns) + " over " + std::to_string(samples));
      s2kf::use_instruction_set(set);
      Eigen::MatrixXd c = c0;
      s2kf::add_product_transposed(c, a, b);
      EXPECT_LE(((c - product).cwiseAbs() - product_bound).maxCoeff(), 0.0);
      Eigen::MatrixXd s = s0;
      s2kf::add_self_product_lower(s, a, -1.0);
      EXPECT_LE(
          ((s - down).triangularView<Eigen::Lower>().toDenseMatrix().cwiseAbs() - down_bound).maxCoeff(),
          0.0);
      EXPECT_TRUE((s.triangularView<Eigen::StrictlyUpper>().toDenseMatrix().array() ==
                   s0.triangularView<Eigen::StrictlyUpper>().toDenseMatrix().array())
                      .all())
          << "a lower update wrote above the diagonal";
      Eigen::MatrixXd t = c0;
      s2kf::add_triangular_product_transposed(t, l, z);
      EXPECT_LE(((t - triangular).cwiseAbs() - triangular_bound).maxCoeff(), 0.0);
      results.push_back({c, s, t});
    }
    const std::vector<InstructionSet> sets = runnable_sets();
    for (std::size_t v = 0; v + 1 < sets.size(); ++v)
      if (sets[v] != InstructionSet::sse2) {
        for (int k = 0; k < 3; ++k) EXPECT_TRUE(results[v][k] == results.back()[k]) << "result " << k;
      }
  }
}

// The bordered factorisation with each variant's tiles: [A; B] -> [L; B L^-T] with L L^T = A and
// X L^T = B to the backward error of a Cholesky factorisation and of a triangular solve
// (|dA| <= gamma_{n+1} |L| |L|^T, Higham 10.1; |dB| <= gamma_n |X| |L|^T), at the filter's sizes
// and at sizes that leave partial tiles and column groups.
TEST(InstructionSet, EveryVariantsBorderedCholeskyHasTheBackwardErrorOfACholeskyFactorisation) {
  const RestoreInstructionSet restore;
  const double u = std::numeric_limits<double>::epsilon() / 2;
  std::mt19937 random(13);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const auto& [size, border] :
       std::vector<std::array<Eigen::Index, 2>>{{46, 47}, {93, 47}, {30, 47}, {7, 3}}) {
    const Eigen::MatrixXd m = Eigen::MatrixXd::NullaryExpr(size, size + 5, [&] { return normal(random); });
    const Eigen::MatrixXd a = m * m.transpose();
    const Eigen::MatrixXd b = Eigen::MatrixXd::NullaryExpr(border, size, [&] { return normal(random); });
    std::vector<Eigen::MatrixXd> panels;
    for (InstructionSet set : runnable_sets()) {
      SCOPED_TRACE(std::string(s2kf::instruction_set_name(set)) + ", size " + std::to_string(size));
      s2kf::use_instruction_set(set);
      s2kf::BorderedCholesky bordered;
      bordered.resize(size, border);
      auto panel = bordered.panel();
      panel.topRows(size).triangularView<Eigen::Lower>() = a;
      panel.bottomRows(border) = b;
      ASSERT_TRUE(bordered.factorise());
      const Eigen::MatrixXd l = panel.topRows(size).triangularView<Eigen::Lower>();
      const Eigen::MatrixXd x = panel.bottomRows(border);
      const double gamma_factor = (size + 1) * u / (1 - (size + 1) * u);
      EXPECT_LE(((l * l.transpose() - a).cwiseAbs() - gamma_factor * l.cwiseAbs() * l.cwiseAbs().transpose())
                    .maxCoeff(),
                0.0);
      EXPECT_LE(((x * l.transpose() - b).cwiseAbs() - gamma_factor * x.cwiseAbs() * l.cwiseAbs().transpose())
                    .maxCoeff(),
                0.0);
      Eigen::MatrixXd result(size + border, size);  // the strict upper half of L is unspecified
      result << l, x;
      panels.push_back(result);
    }
    const std::vector<InstructionSet> sets = runnable_sets();
    for (std::size_t v = 0; v + 1 < sets.size(); ++v)
      if (sets[v] != InstructionSet::sse2) {
        EXPECT_TRUE(panels[v] == panels.back()) << "fused variants differ";
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
