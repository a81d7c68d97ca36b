// formatNumber: the shortest text that reads back to the same double, in %g's notation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>

#include "rail_contact/format.hpp"

using rail::contact::formatNumber;

TEST(FormatNumber, KeepsPrintfGTextWhereItWasExact) {
  EXPECT_EQ(formatNumber(0.0), "0");
  EXPECT_EQ(formatNumber(-0.0), "-0");
  EXPECT_EQ(formatNumber(0.5), "0.5");
  EXPECT_EQ(formatNumber(30.0), "30");
  EXPECT_EQ(formatNumber(-500.0), "-500");
  EXPECT_EQ(formatNumber(100000.0), "100000");
  EXPECT_EQ(formatNumber(1e6), "1e+06");
  EXPECT_EQ(formatNumber(2e12), "2e+12");
  EXPECT_EQ(formatNumber(1e-4), "0.0001");
  EXPECT_EQ(formatNumber(2e-5), "2e-05");
  EXPECT_EQ(formatNumber(-1e300), "-1e+300");
}

TEST(FormatNumber, ShowsEveryDigitNeeded) {
  EXPECT_EQ(formatNumber(1.23456789), "1.23456789");  // %g: 1.23457
  EXPECT_EQ(formatNumber(0.1 + 0.2), "0.30000000000000004");
  EXPECT_EQ(formatNumber(1234567.0), "1234567");  // %g: 1.23457e+06
  EXPECT_EQ(formatNumber(100000.5), "100000.5");
  EXPECT_EQ(formatNumber(std::numeric_limits<double>::max()), "1.7976931348623157e+308");
  EXPECT_EQ(formatNumber(std::numeric_limits<double>::denorm_min()), "5e-324");
}

TEST(FormatNumber, NotFinite) {
  EXPECT_EQ(formatNumber(std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(formatNumber(-std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(formatNumber(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(formatNumber(-std::numeric_limits<double>::infinity()), "-inf");
}

TEST(FormatNumber, ReadsBackToTheSameDouble) {
  std::mt19937_64 bits(7);
  for (int i = 0; i < 200000; ++i) {
    const std::uint64_t b = bits();
    double v;
    std::memcpy(&v, &b, sizeof v);
    if (!std::isfinite(v)) continue;
    const std::string text = formatNumber(v);
    ASSERT_EQ(std::strtod(text.c_str(), nullptr), v) << text;
  }
}
