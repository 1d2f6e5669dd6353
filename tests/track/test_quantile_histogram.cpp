// The fixed-memory statistics of a stream (track/quantile_histogram.hpp): quantiles within the
// stated relative resolution of the exact ones (track::quantile, a sort) on random data of several
// shapes and sizes; count, sum, mean, min and max exact; the edge cases (no value, one value, NaN and
// infinities skipped, values outside the bins' range) and memory that does not grow.
#include <s2kf/track/quantile_histogram.hpp>
#include <s2kf/track/tracking_metrics.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace s2kf::track {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const std::vector<double> kLevels = {0, 0.001, 0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99, 0.999, 1};

/// Expects every level's quantile of `h` within its resolution of the exact quantile of `values`.
void expect_within_resolution(const QuantileHistogram& h, const std::vector<double>& values) {
  for (double q : kLevels) {
    const double exact = quantile(values, q);
    // The bins' edges come from a logarithm: a value on an edge may land one bin over, a rounding's worth.
    EXPECT_LE(std::abs(h.quantile(q) - exact), (h.resolution() + 1e-12) * std::abs(exact))
        << "q " << q << " of " << values.size() << " values: " << h.quantile(q) << " against " << exact;
  }
}

TEST(QuantileHistogram, QuantilesOfRandomDataAreWithinTheResolutionOfTheSortedData) {
  std::mt19937_64 random(7);
  std::lognormal_distribution<double> latency(std::log(0.5), 0.6);  // ms: a heavy right tail
  std::uniform_real_distribution<double> distance(2, 40);           // mm
  std::exponential_distribution<double> seconds(2000);              // s: many near zero
  for (std::size_t n : {2, 3, 10, 101, 1000, 20000}) {
    for (int shape = 0; shape < 3; ++shape) {
      QuantileHistogram h;
      std::vector<double> values;
      for (std::size_t i = 0; i < n; ++i) {
        const double v = shape == 0 ? latency(random) : shape == 1 ? distance(random) : seconds(random);
        values.push_back(v);
        h.add(v);
      }
      SCOPED_TRACE("shape " + std::to_string(shape));
      expect_within_resolution(h, values);
      double sum = 0;
      for (double v : values) sum += v;
      EXPECT_EQ(h.count(), static_cast<std::int64_t>(n));
      EXPECT_EQ(h.sum(), sum);  // added in the same order
      EXPECT_EQ(h.mean(), sum / static_cast<double>(n));
      EXPECT_EQ(h.min(), quantile(values, 0));
      EXPECT_EQ(h.max(), quantile(values, 1));
    }
  }
}

TEST(QuantileHistogram, ACoarserResolutionIsKeptToo) {
  std::mt19937_64 random(11);
  std::lognormal_distribution<double> values_of(0, 2);
  QuantileHistogram h(0.05);
  std::vector<double> values;
  for (int i = 0; i < 5000; ++i) values.push_back(values_of(random)), h.add(values.back());
  expect_within_resolution(h, values);
  // And the resolution is not better than stated: some quantile is off by more than a tenth of it.
  double worst = 0;
  for (double q : kLevels) worst = std::max(worst, std::abs(h.quantile(q) / quantile(values, q) - 1));
  EXPECT_GT(worst, 0.005);
  EXPECT_LT(h.bin_count(), QuantileHistogram().bin_count());
}

TEST(QuantileHistogram, WithoutValuesEverythingButTheCountIsNaN) {
  QuantileHistogram h;
  EXPECT_EQ(h.count(), 0);
  EXPECT_EQ(h.sum(), 0);
  EXPECT_TRUE(std::isnan(h.mean()));
  EXPECT_TRUE(std::isnan(h.min()));
  EXPECT_TRUE(std::isnan(h.max()));
  EXPECT_TRUE(std::isnan(h.quantile(0.5)));
}

TEST(QuantileHistogram, OneValueIsEveryQuantileExactly) {
  QuantileHistogram h;
  h.add(0.4321);
  for (double q : kLevels) EXPECT_EQ(h.quantile(q), 0.4321);
  EXPECT_EQ(h.mean(), 0.4321);
}

TEST(QuantileHistogram, NaNAndInfinitiesAreSkipped) {
  QuantileHistogram h;
  for (double v :
       {kNaN, 1.0, std::numeric_limits<double>::infinity(), 3.0, -std::numeric_limits<double>::infinity()})
    h.add(v);
  EXPECT_EQ(h.count(), 2);
  EXPECT_EQ(h.mean(), 2.0);
  EXPECT_EQ(h.max(), 3.0);
  EXPECT_NEAR(h.quantile(0.5), 2.0, 0.005 * 2.0);
  EXPECT_TRUE(std::isnan(h.quantile(kNaN)));
  // Levels outside 0..1 are the extremes.
  EXPECT_EQ(h.quantile(-1), 1.0);
  EXPECT_EQ(h.quantile(2), 3.0);
}

TEST(QuantileHistogram, ValuesOutsideTheRangeAreReportedWithinTheValuesSeen) {
  QuantileHistogram h(0.005, 1e-3, 1e3);
  // Zeros and tiny values share the bottom bin (reported as the smallest value), huge ones the top
  // bin (reported as the largest); the bins between keep their resolution. Ranks 0 to 8:
  for (double v : {0.0, 0.0, 1e-6, 2.0, 4.0, 8.0, 5e5, 2e6, 3e7}) h.add(v);
  EXPECT_EQ(h.quantile(0), 0);
  EXPECT_EQ(h.quantile(0.25), 0);  // rank 2, 1e-6: below the range
  EXPECT_NEAR(h.quantile(0.5), 4, 0.005 * 4);
  EXPECT_NEAR(h.quantile(0.625), 8, 0.005 * 8);
  EXPECT_EQ(h.quantile(0.75), 3e7);  // rank 6, 5e5: above the range
  EXPECT_EQ(h.quantile(1), 3e7);
  EXPECT_EQ(h.min(), 0);
  EXPECT_EQ(h.max(), 3e7);
  for (double q : kLevels) {
    EXPECT_GE(h.quantile(q), h.min());
    EXPECT_LE(h.quantile(q), h.max());
  }
}

TEST(QuantileHistogram, MemoryDoesNotGrowWithTheValues) {
  QuantileHistogram h;
  const std::size_t bins = h.bin_count();
  EXPECT_EQ(bins, 4147u);  // 0.5 % over [1e-9, 1e9], and the two outer bins
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> any(0, 1e10);
  for (int i = 0; i < 100000; ++i) h.add(any(random));
  EXPECT_EQ(h.bin_count(), bins);
  EXPECT_EQ(h.count(), 100000);
}

}  // namespace
}  // namespace s2kf::track
