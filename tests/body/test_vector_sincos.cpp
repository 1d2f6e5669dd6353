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

TEST(VectorSinCos, SinglePrecisionAgreesWithTheStandardLibraryToAFewFloatUlps) {
  std::mt19937 rng(2);
  std::vector<float> x;
  for (float scale : {1e-6f, 0.7f, 3.5f, 20.0f, 1e3f, 8e3f}) {
    std::uniform_real_distribution<float> unit(-scale, scale);
    for (int k = 0; k < 2000; ++k) x.push_back(unit(rng));
  }
  for (int k = -40; k <= 40; ++k) x.push_back(static_cast<float>(k * M_PI / 4));
  x.push_back(0.0f);
  std::vector<float> s(x.size()), c(x.size());
  s2kf::body::vector_sincos(x.data(), s.data(), c.data(), static_cast<Eigen::Index>(x.size()));
  for (std::size_t i = 0; i < x.size(); ++i) {
    // Against the double-precision functions of the same float argument: float's unit roundoff
    // (6e-8) a few times over, and the argument's own rounding for large |x|.
    const double xi = x[i], tol = 2.4e-7 * std::max(1.0, std::abs(xi) / 100);
    EXPECT_NEAR(s[i], std::sin(xi), tol) << xi;
    EXPECT_NEAR(c[i], std::cos(xi), tol) << xi;
  }
  std::vector<float> odd{1e5f, -3e7f, std::numeric_limits<float>::quiet_NaN()};
  std::vector<float> so(odd.size()), co(odd.size());
  s2kf::body::vector_sincos(odd.data(), so.data(), co.data(), static_cast<Eigen::Index>(odd.size()));
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(so[i], static_cast<float>(std::sin(static_cast<double>(odd[i]))));
    EXPECT_EQ(co[i], static_cast<float>(std::cos(static_cast<double>(odd[i]))));
  }
  EXPECT_TRUE(std::isnan(so[2]) && std::isnan(co[2]));
}

}  // namespace
