// The occlusion processes: the paper's random Poisson gaps and the planned dropouts.
#include <s2kf/sim/occlusion.hpp>
#include <s2kf/sim/random.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace {

using namespace s2kf::sim;

// The exact expected fraction of hidden frames over a recording of `frames` frames that starts
// with every marker visible, by propagating the distribution of one marker's state (the number of
// hidden frames still to come) through the process frame by frame. Independent of the simulator.
double expected_hidden_fraction(double p, double lambda, int frames) {
  const int max_gap = static_cast<int>(lambda + 20 * std::sqrt(lambda) + 50);
  std::vector<double> gap(max_gap + 1);  // Poisson pmf, computed in logs
  for (int n = 0; n <= max_gap; ++n) gap[n] = std::exp(n * std::log(lambda) - lambda - std::lgamma(n + 1.0));
  std::vector<double> remaining(max_gap + 1, 0.0);  // P(r frames still hidden, including this one)
  remaining[0] = 1.0;
  double hidden_sum = 0.0;
  for (int k = 0; k < frames; ++k) {
    std::vector<double> next(max_gap + 1, 0.0), current = remaining;
    // A visible marker starts a gap of n frames from this frame with probability p gap[n].
    const double visible = current[0];
    current[0] = visible * (1.0 - p + p * gap[0]);
    for (int n = 1; n <= max_gap; ++n) current[n] += visible * p * gap[n];
    double hidden = 0.0;
    for (int r = 1; r <= max_gap; ++r) {
      hidden += current[r];
      next[r - 1] += current[r];
    }
    next[0] += current[0];
    hidden_sum += hidden;
    remaining = next;
  }
  return hidden_sum / frames;
}

TEST(RandomOcclusion, TheDynamicProgramAgreesWithTheStationaryFormula) {
  // Long recordings forget the all-visible start (the deficit of the first frames is about 11
  // marker-frames, 5e-4 over 20000 frames); the formula is derived independently.
  const RandomOcclusion paper{kPaperOcclusionProbability, kPaperOcclusionMeanFrames};
  EXPECT_NEAR(expected_hidden_fraction(0.005, 100, 20000), stationary_hidden_fraction(paper), 2e-3);
  EXPECT_NEAR(stationary_hidden_fraction(paper), 0.5 / 1.495, 1e-12);
  EXPECT_NEAR(stationary_hidden_fraction(paper), 0.005 * 100 / (1 + 0.005 * 100), 2e-3);
}

// The paper's experiment: 100 Monte Carlo runs of a 675-frame recording with 50 markers. The mean
// hidden fraction must match the exact expectation within 4 standard errors (the runs are
// independent, so their spread gives an honest error despite the 100-frame correlation inside a run).
TEST(RandomOcclusion, HiddenFractionOfThePapersExperimentMatchesTheExactExpectation) {
  const RandomOcclusion paper{0.005, 100};
  const int runs = 100, markers = 50, frames = 675;
  std::vector<double> fractions;
  for (int run = 0; run < runs; ++run) {
    std::mt19937_64 rng(derive_seed(2024, static_cast<std::uint64_t>(run)));
    Visibility visible = Visibility::Constant(markers, frames, true);
    apply_random_occlusion(visible, paper, rng);
    fractions.push_back(1.0 - visible.cast<double>().mean());
  }
  double mean = 0.0, variance = 0.0;
  for (double f : fractions) mean += f / runs;
  for (double f : fractions) variance += (f - mean) * (f - mean) / (runs - 1);
  const double standard_error = std::sqrt(variance / runs);
  const double expected = expected_hidden_fraction(0.005, 100, frames);
  EXPECT_NEAR(mean, expected, 4 * standard_error) << "expected " << expected * markers << " of 50 hidden";
  // The paper reports 16 of 50 hidden on average over its 100 runs; the exact expectation for
  // 675 frames from an all-visible start is 15.9 (below the stationary 16.7: gaps take a while
  // to build up).
  EXPECT_NEAR(expected * markers, 16.0, 0.3);
}

TEST(RandomOcclusion, LongRunHiddenFractionAndGapLengthMatchTheProcess) {
  const RandomOcclusion occlusion{0.005, 100};
  const int markers = 50, frames = 20000;
  std::mt19937_64 rng(99);
  Visibility visible = Visibility::Constant(markers, frames, true);
  apply_random_occlusion(visible, occlusion, rng);
  // Gaps that end before the last frame are complete; their lengths are Poisson(100) draws
  // conditioned on >= 1 frame (mean 100, SD 10). Back-to-back gaps merge, rarely (p per frame).
  long gaps = 0;
  double total = 0.0, total_squared = 0.0;
  for (int m = 0; m < markers; ++m) {
    int run = 0;
    for (int k = 0; k < frames; ++k) {
      if (!visible(m, k)) {
        ++run;
      } else if (run > 0) {
        ++gaps;
        total += run;
        total_squared += double(run) * run;
        run = 0;
      }
    }
  }
  ASSERT_GT(gaps, 2000);
  const double mean_gap = total / gaps;
  const double sd_gap = std::sqrt(total_squared / gaps - mean_gap * mean_gap);
  // Merged gaps (probability ~ p per gap) add about p * 100 = 0.5 frames to the mean.
  EXPECT_NEAR(mean_gap, 100.5, 4 * sd_gap / std::sqrt(double(gaps)) + 0.5);
  EXPECT_GT(sd_gap, 8.0);
  EXPECT_LT(sd_gap, 20.0);
  // The hidden fraction over the last 15000 frames (start-up forgotten): 4 SE of a per-marker
  // estimate, with the markers as independent replicates.
  std::vector<double> per_marker;
  for (int m = 0; m < markers; ++m)
    per_marker.push_back(1.0 - visible.row(m).segment(5000, 15000).cast<double>().mean());
  double mean = 0.0, variance = 0.0;
  for (double f : per_marker) mean += f / markers;
  for (double f : per_marker) variance += (f - mean) * (f - mean) / (markers - 1);
  EXPECT_NEAR(mean, stationary_hidden_fraction(occlusion), 4 * std::sqrt(variance / markers));
}

TEST(RandomOcclusion, ZeroProbabilityHidesNothingAndOneHidesAlmostEverything) {
  std::mt19937_64 rng(1);
  Visibility visible = Visibility::Constant(10, 500, true);
  apply_random_occlusion(visible, RandomOcclusion{0.0, 100}, rng);
  EXPECT_TRUE(visible.all());
  apply_random_occlusion(visible, RandomOcclusion{1.0, 100}, rng);
  // With p = 1 a marker is visible only after a gap of 0 frames (probability e^-100).
  EXPECT_FALSE(visible.any());
}

TEST(RandomOcclusion, RejectsImpossibleParameters) {
  std::mt19937_64 rng(1);
  Visibility visible = Visibility::Constant(2, 5, true);
  EXPECT_THROW(apply_random_occlusion(visible, RandomOcclusion{-0.1, 100}, rng), std::invalid_argument);
  EXPECT_THROW(apply_random_occlusion(visible, RandomOcclusion{1.5, 100}, rng), std::invalid_argument);
  EXPECT_THROW(apply_random_occlusion(visible, RandomOcclusion{0.1, -1}, rng), std::invalid_argument);
  EXPECT_THROW(apply_random_occlusion(visible, RandomOcclusion{std::nan(""), 100}, rng),
               std::invalid_argument);
}

TEST(Poisson, MeanAndVarianceMatchLambdaAboveAndBelowTheSplit) {
  for (double lambda : {0.7, 100.0, 250.0}) {
    std::mt19937_64 rng(5);
    const int n = 20000;
    double sum = 0, sum_squared = 0;
    for (int i = 0; i < n; ++i) {
      const double x = static_cast<double>(poisson(rng, lambda));
      sum += x;
      sum_squared += x * x;
    }
    const double mean = sum / n, variance = sum_squared / n - mean * mean;
    EXPECT_NEAR(mean, lambda, 4 * std::sqrt(lambda / n)) << lambda;
    EXPECT_NEAR(variance / lambda, 1.0, 0.06) << lambda;
  }
}

TEST(StandardNormal, HasZeroMeanAndUnitVariance) {
  std::mt19937_64 rng(11);
  const int n = 100000;
  double sum = 0, sum_squared = 0, beyond_two = 0;
  for (int i = 0; i < n; ++i) {
    const double x = standard_normal(rng);
    sum += x;
    sum_squared += x * x;
    beyond_two += std::abs(x) > 2.0;
  }
  EXPECT_NEAR(sum / n, 0.0, 4 / std::sqrt(double(n)));
  EXPECT_NEAR(sum_squared / n, 1.0, 4 * std::sqrt(2.0 / n));
  EXPECT_NEAR(beyond_two / n, 0.0455, 4 * std::sqrt(0.0455 * 0.9545 / n));
}

TEST(Hide, ClipsToTheRecordingAndConvertsTimesToFrames) {
  Visibility visible = Visibility::Constant(3, 100, true);
  const auto [first, count] = frames_of_interval(0.5, 1.0, 100.0);
  EXPECT_EQ(first, 50);
  EXPECT_EQ(count, 100);
  hide(visible, {1}, first, count);
  EXPECT_EQ(visible.row(1).cast<int>().sum(), 50);
  EXPECT_TRUE(visible.row(1).head(50).all());
  EXPECT_EQ(visible.row(0).cast<int>().sum(), 100);
  EXPECT_THROW(hide(visible, {3}, 0, 1), std::out_of_range);
  EXPECT_THROW(frames_of_interval(-1.0, 1.0, 100.0), std::invalid_argument);
}

}  // namespace
