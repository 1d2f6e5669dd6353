// The fast number writers must give exactly the text an ostream gives with the same precision
// (the motion files were written through ostreams before, and readers and tests compare them).
#include <s2kf/io/number_text.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

std::string through_ostream(double value, int precision, bool fixed) {
  std::ostringstream out;
  if (fixed) out << std::fixed;
  out << std::setprecision(precision) << value;
  return out.str();
}

std::string through_writer(double value, int precision, bool fixed) {
  std::ostringstream out;
  if (fixed)
    s2kf::io::write_fixed(out, value, precision);
  else
    s2kf::io::write_general(out, value, precision);
  return out.str();
}

std::vector<double> test_values() {
  std::vector<double> values = {0.0,
                                -0.0,
                                1.0,
                                -1.5,
                                0.1,
                                1e-7,
                                123456789.0,
                                1234567890123.0,
                                0.000123456789012,
                                2.5e-300,
                                -1.7976931348623157e308,
                                std::numeric_limits<double>::denorm_min(),
                                0.5,
                                9.9999999995,
                                999999.9999995,
                                std::numeric_limits<double>::quiet_NaN(),
                                std::numeric_limits<double>::infinity(),
                                -std::numeric_limits<double>::infinity()};
  std::mt19937_64 random(17);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-12, 12);
  for (int k = 0; k < 20000; ++k) values.push_back(mantissa(random) * std::pow(10.0, exponent(random)));
  return values;
}

TEST(NumberText, GeneralFormatEqualsTheOstreamsAtEveryPrecisionUsed) {
  int compared = 0;
  for (const double value : test_values())
    for (const int precision : {6, 9, 10, 12}) {
      ASSERT_EQ(through_writer(value, precision, false), through_ostream(value, precision, false))
          << "value " << std::setprecision(17) << value << ", precision " << precision;
      ++compared;
    }
  EXPECT_EQ(compared, 4 * 20018);
}

TEST(NumberText, FixedFormatEqualsTheOstreams) {
  for (const double value : test_values()) {
    if (std::isfinite(value) && std::abs(value) > 1e40) continue;  // longer than any angle or mm
    ASSERT_EQ(through_writer(value, 6, true), through_ostream(value, 6, true))
        << "value " << std::setprecision(17) << value;
  }
  // Beyond the buffer: the writer falls back to the ostream, with the same text.
  EXPECT_EQ(through_writer(-1.7976931348623157e308, 6, true),
            through_ostream(-1.7976931348623157e308, 6, true));
  // ... and leaves the stream's format as it found it: the numbers written after it are the caller's.
  std::ostringstream out;
  out << std::setprecision(3);
  s2kf::io::write_fixed(out, 1e300, 2);
  out << ' ' << 1.0 / 3.0;
  EXPECT_EQ(out.str().substr(out.str().size() - 6), " 0.333");
  EXPECT_EQ(out.precision(), 3);
  EXPECT_FALSE(out.flags() & std::ios_base::fixed);
  EXPECT_EQ(through_writer(12.5, 6, true), "12.500000");
  EXPECT_EQ(through_writer(0.1, 9, false), "0.1");
  EXPECT_EQ(through_writer(1.0 / 3.0, 9, false), "0.333333333");
}

}  // namespace
