// The vectorised sine/cosine against std::sin and std::cos.
#include <s2kf/body/vector_sincos.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace {

TEST(VectorSinCos, AgreesWithTheStandardLibraryToAFewUlps) {
  std::mt19937 rng(1);
  std::vector<double> x;
  for (double scale : {1e-9, 1e-3, 0.7, 3.5, 20.0, 1e3, 9e4}) {
    std::uniform_real_distribution<double> unit(-scale, scale);
    for (int k = 0; k < 2000; ++k) x.push_back(unit(rng));
  }
  // Quadrant edges and exact multiples of pi/4, where the reduction switches branches.
  for (int k = -40; k <= 40; ++k)
    for (double eps : {-1e-12, 0.0, 1e-12}) x.push_back(k * M_PI / 4 + eps);
  x.push_back(0.0);
  x.push_back(-0.0);
  std::vector<double> s(x.size()), c(x.size());
  s2kf::body::vector_sincos(x.data(), s.data(), c.data(), static_cast<Eigen::Index>(x.size()));
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double tol = 4e-16 * std::max(1.0, std::abs(x[i]) / 100);
    EXPECT_NEAR(s[i], std::sin(x[i]), tol) << x[i];
    EXPECT_NEAR(c[i], std::cos(x[i]), tol) << x[i];
  }
}

TEST(VectorSinCos, LargeAndNonFiniteArgumentsBehaveLikeTheStandardLibrary) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  std::vector<double> x{1e6, -1e9, 1e300, nan, inf, -inf, 0.5};
  std::vector<double> s(x.size()), c(x.size());
  s2kf::body::vector_sincos(x.data(), s.data(), c.data(), static_cast<Eigen::Index>(x.size()));
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(s[i], std::sin(x[i]));
    EXPECT_EQ(c[i], std::cos(x[i]));
  }
  for (std::size_t i = 3; i < 6; ++i) {
    EXPECT_TRUE(std::isnan(s[i]));
    EXPECT_TRUE(std::isnan(c[i]));
  }
  EXPECT_NEAR(s[6], std::sin(0.5), 1e-16);
}

}  // namespace
