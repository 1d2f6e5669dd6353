// The program's joint angles with every kernel variant this build and processor run (S2KF_SIMD):
// AVX2 and AVX-512 sum in the same order and fuse the same multiply-adds, in the float moment tiles
// and the double ones (rank updates, sample draw, bordered Cholesky) alike, so they give the same
// motion to 1e-9 (each kernel against Eigen on random inputs: tests/core/test_instruction_set.cpp); SSE2 has
// no fused multiply-add (processors before 2013), each single-precision product rounds once more, and the
// filter carries that to a few 1e-6 rad. (In a test program the kernels' inline copies compiled at -O1 may be
// the ones linked, so this runs the program itself.)
#include <s2kf/core/instruction_set.hpp>

#include "cli_runner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#ifdef S2KF_CLI

namespace {

using s2kf::InstructionSet;

/// The joint angles and root position of a tracked CSV: one row of numbers per frame.
std::vector<std::vector<double>> motion_rows(const std::string& path) {
  const auto rows = s2kf::test_support::csv_rows(s2kf::test_support::read_text(path));
  std::vector<std::vector<double>> numbers;
  for (std::size_t r = 1; r < rows.size(); ++r) {
    std::vector<double> row;
    for (std::size_t c = 2; c < rows[r].size(); ++c) row.push_back(std::stod(rows[r][c]));
    numbers.push_back(row);
  }
  return numbers;
}

/// Largest difference of the root position (columns 0-2, mm) and of the angles (the rest, rad).
std::pair<double, double> largest_differences(const std::vector<std::vector<double>>& a,
                                              const std::vector<std::vector<double>>& b) {
  double mm = 0, rad = 0;
  for (std::size_t r = 0; r < a.size(); ++r)
    for (std::size_t c = 0; c < a[r].size(); ++c)
      (c < 3 ? mm : rad) = std::max(c < 3 ? mm : rad, std::abs(a[r][c] - b[r][c]));
  return {mm, rad};
}

TEST(KernelVariants, TrackingGivesTheSameMotionWithEveryVariant) {
  std::vector<InstructionSet> sets;
  for (int s = static_cast<int>(s2kf::compiled_instruction_set());
       s <= static_cast<int>(s2kf::supported_instruction_set()); ++s)
    sets.push_back(static_cast<InstructionSet>(s));
  if (sets.size() < 2) GTEST_SKIP() << "this build runs one kernel variant only (compiled for it)";

  const std::string recording =
      s2kf::test_support::simulate_with_program("variants", "--motion walk --seed 5 --frames 150") + ".c3d";
  std::vector<std::vector<std::vector<double>>> motions;
  for (InstructionSet set : sets) {
    const std::string name = s2kf::instruction_set_name(set);
    ::setenv("S2KF_SIMD", name.c_str(), 1);
    const std::string out = (s2kf::test_support::scratch("variants") / name).string();
    const auto run = s2kf::test_support::run_command("track " + recording +
                                                     " --no-calibrate --formats csv --quiet --out " + out);
    ::unsetenv("S2KF_SIMD");
    ASSERT_EQ(run.status, 0) << run.output;
    motions.push_back(motion_rows(out + ".csv"));
    ASSERT_EQ(motions.back().size(), 150u) << name;
  }
  for (std::size_t v = 0; v + 1 < sets.size(); ++v) {
    const auto [mm, rad] = largest_differences(motions[v], motions.back());
    SCOPED_TRACE(std::string(s2kf::instruction_set_name(sets[v])) + " against " +
                 s2kf::instruction_set_name(sets.back()) + ": " + std::to_string(rad) + " rad, " +
                 std::to_string(mm) + " mm");
    const bool fused = sets[v] != InstructionSet::sse2;
    EXPECT_LE(rad, fused ? 1e-9 : 1e-5);
    EXPECT_LE(mm, fused ? 1e-9 : 1e-3);
  }
}

}  // namespace

#endif
