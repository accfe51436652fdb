// details::line_minimum (Brent's method) finds a smooth minimum within its tolerance in fewer
// evaluations than golden sections need for the same bracket, keeps to its bracket where the
// minimum lies outside it, never returns worse than its start, and stops at its evaluation cap.
#include "details/line_minimum.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hd = hystbench::compensation::details;

namespace {

// Golden sections shrink the bracket by 0.618 per evaluation.
int golden_evaluations(double width, double tolerance) {
  return static_cast<int>(std::ceil(std::log(2.0 * tolerance / width) / std::log(0.618))) + 2;
}

}  // namespace

TEST(LineMinimum, FindsASmoothMinimumWithinItsToleranceInFewerEvaluationsThanGoldenSections) {
  // An error like a search's: quadratic about its minimum, with a quartic term.
  const double at = 0.37;
  int calls = 0;
  const auto f = [&](double x) {
    ++calls;
    const double d = x - at;
    return 2.0 + 3.0 * d * d + 5.0 * d * d * d * d;
  };
  const double a = -0.3, b = 0.9, x0 = 0.1, tolerance = 1e-3;
  const hd::LineMinimum m = hd::line_minimum(f, a, b, x0, f(x0), tolerance, 50);
  EXPECT_NEAR(m.x, at, 2.0 * tolerance);
  EXPECT_NEAR(m.value, f(m.x), 1e-15);
  EXPECT_EQ(calls, m.evaluations + 2);  // the start's, above, and this check's
  EXPECT_LT(m.evaluations, golden_evaluations(b - a, tolerance) / 2) << m.evaluations;
}

TEST(LineMinimum, KeepsToItsBracketWhereTheMinimumLiesBeyondIt) {
  const auto f = [](double x) { return (x - 3.0) * (x - 3.0); };
  const hd::LineMinimum m = hd::line_minimum(f, 0.0, 1.0, 0.5, f(0.5), 1e-4, 60);
  EXPECT_LE(m.x, 1.0);
  EXPECT_NEAR(m.x, 1.0, 3e-4);
  EXPECT_LT(m.value, f(0.5));
}

TEST(LineMinimum, NeverReturnsWorseThanItsStart) {
  // A start at the minimum of a function with a lower, narrow dip elsewhere it may not find.
  const auto f = [](double x) { return std::abs(x) < 1e-9 ? -1.0 : std::abs(x - 0.8); };
  const hd::LineMinimum m = hd::line_minimum(f, 0.0, 1.0, 0.8, f(0.8), 1e-3, 40);
  EXPECT_LE(m.value, f(0.8));
  EXPECT_NEAR(m.x, 0.8, 2e-3);
}

TEST(LineMinimum, StopsAtItsEvaluationCap) {
  int calls = 0;
  const auto f = [&](double x) {
    ++calls;
    return std::cos(40.0 * x) + x;
  };
  const hd::LineMinimum m = hd::line_minimum(f, 0.0, 10.0, 5.0, f(5.0), 1e-12, 7);
  EXPECT_EQ(m.evaluations, 7);
  EXPECT_EQ(calls, 8);
  EXPECT_LE(m.value, f(5.0));
}
