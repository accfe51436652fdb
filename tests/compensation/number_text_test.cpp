// Numbers as text (number_text): the exact strings of each form for typical, zero, negative,
// not-a-number, infinite and large values.
#include "hystbench/compensation/number_text.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace hc = hystbench::compensation;

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(NumberText, SignificantRoundsToItsDigitsAndDropsTrailingZeros) {
  EXPECT_EQ(hc::significant(200.027, 6), "200.027");
  EXPECT_EQ(hc::significant(200.027, 3), "200");
  EXPECT_EQ(hc::significant(1.0 / 3.0, 3), "0.333");
  EXPECT_EQ(hc::significant(0.5, 6), "0.5");
  EXPECT_EQ(hc::significant(0.000125, 3), "0.000125");
  EXPECT_EQ(hc::significant(2.675, 3), "2.67");  // 2.675 is 2.67499999... as a double
  EXPECT_EQ(hc::significant(0.0, 3), "0");
  EXPECT_EQ(hc::significant(-12.5, 3), "-12.5");
  EXPECT_EQ(hc::significant(0.1, 17), "0.10000000000000001");
}

TEST(NumberText, SignificantWritesLargeAndSmallValuesWithAnExponent) {
  EXPECT_EQ(hc::significant(20000.0, 3), "2e+04");
  EXPECT_EQ(hc::significant(20000.0, 6), "20000");
  EXPECT_EQ(hc::significant(1.25e6, 6), "1.25e+06");
  EXPECT_EQ(hc::significant(123456789.0, 6), "1.23457e+08");
  EXPECT_EQ(hc::significant(1e300, 6), "1e+300");
  EXPECT_EQ(hc::significant(1e-5, 6), "1e-05");
}

TEST(NumberText, FixedKeepsItsDecimals) {
  EXPECT_EQ(hc::fixed(200.027, 3), "200.027");
  EXPECT_EQ(hc::fixed(0.5, 3), "0.500");
  EXPECT_EQ(hc::fixed(2.675, 0), "3");
  EXPECT_EQ(hc::fixed(2.5, 0), "2");  // ties to even, as printf
  EXPECT_EQ(hc::fixed(0.0, 3), "0.000");
  EXPECT_EQ(hc::fixed(-12.5, 3), "-12.500");
  EXPECT_EQ(hc::fixed(-0.000125, 3), "-0.000");
  EXPECT_EQ(hc::fixed(1.25e6, 1), "1250000.0");
  EXPECT_EQ(hc::fixed(1e16, 0), "10000000000000000");
}

TEST(NumberText, PercentScalesAFractionAndAddsTheSign) {
  EXPECT_EQ(hc::percent(0.125, 3), "12.5 %");
  EXPECT_EQ(hc::percent(1.0 / 3.0, 3), "33.3 %");
  EXPECT_EQ(hc::percent(0.5, 3), "50 %");
  EXPECT_EQ(hc::percent(2.5, 3), "250 %");
  EXPECT_EQ(hc::percent(0.0, 3), "0 %");
  EXPECT_EQ(hc::percent(-0.125, 3), "-12.5 %");
  EXPECT_EQ(hc::percent(1e-5, 3), "0.001 %");
  EXPECT_EQ(hc::percent(1234.5, 3), "1.23e+05 %");
}

TEST(NumberText, ShortestReadsBackToTheSameValue) {
  EXPECT_EQ(hc::shortest(0.1), "0.1");
  EXPECT_EQ(hc::shortest(1.0 / 3.0), "0.3333333333333333");
  EXPECT_EQ(hc::shortest(200.027), "200.027");
  EXPECT_EQ(hc::shortest(20000.0), "20000");
  EXPECT_EQ(hc::shortest(0.0), "0");
  EXPECT_EQ(hc::shortest(-12.5), "-12.5");
  EXPECT_EQ(hc::shortest(1e-5), "1e-05");
  EXPECT_EQ(hc::shortest(123456789.0), "123456789");
  EXPECT_EQ(hc::shortest(1e16), "1e+16");
  EXPECT_EQ(hc::shortest(1e300), "1e+300");
}

TEST(NumberText, ValuesThatAreNotFiniteReadAsPrintfWritesThem) {
  EXPECT_EQ(hc::significant(kNan, 6), "nan");
  EXPECT_EQ(hc::significant(-kNan, 6), "-nan");
  EXPECT_EQ(hc::significant(kInf, 6), "inf");
  EXPECT_EQ(hc::significant(-kInf, 6), "-inf");
  EXPECT_EQ(hc::fixed(kNan, 3), "nan");
  EXPECT_EQ(hc::fixed(-kInf, 3), "-inf");
  EXPECT_EQ(hc::percent(kNan, 3), "nan %");
  EXPECT_EQ(hc::shortest(kNan), "nan");
  EXPECT_EQ(hc::shortest(kInf), "inf");
}

}  // namespace
