#include "hystbench/compensation/period_average.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace hc = hystbench::compensation;

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
}  // namespace

// A 19 Hz reference at 10 kHz: 526.3 samples a period. Whatever repeats with it (the
// fundamental, harmonics, a triangle's corners) averages out; the mean stays.
TEST(PeriodAverage, RemovesWhatRepeatsWithAFractionalPeriodAndKeepsTheMean) {
  const double n = 10000.0 / 19.0;
  hc::PeriodAverage avg(n);
  EXPECT_DOUBLE_EQ(avg.period_samples(), n);
  double worst = 0.0;
  for (int k = 0; k < 20 * static_cast<int>(n); ++k) {
    const double ph = kTwoPi * k / n;
    const double x = 0.3 + std::sin(ph) + 0.5 * std::sin(2.0 * ph + 1.0) +
                     0.2 * std::asin(std::sin(3.0 * ph)) + 0.1 * std::cos(7.0 * ph);
    const double a = avg.step(x);
    if (k > 2 * n) worst = std::max(worst, std::abs(a - 0.3));
  }
  // The fraction of the oldest sample is weighted linearly: a residue of order 1/n^2.
  EXPECT_LT(worst, 2e-4);
}

TEST(PeriodAverage, AStepAppearsOverOnePeriodFromAZeroHistory) {
  hc::PeriodAverage avg(100.0);
  double a = 0.0;
  for (int k = 0; k < 50; ++k) a = avg.step(2.0);
  EXPECT_NEAR(a, 1.0, 1e-12);  // half the window holds the step
  for (int k = 50; k < 100; ++k) a = avg.step(2.0);
  EXPECT_NEAR(a, 2.0, 1e-12);
  for (int k = 0; k < 100000; ++k) a = avg.step(2.0);
  EXPECT_NEAR(a, 2.0, 1e-12);  // the running sum does not drift
  avg.reset();
  EXPECT_NEAR(avg.step(2.0), 0.02, 1e-12);
}

TEST(PeriodAverage, AWindowShorterThanASamplePassesTheInput) {
  hc::PeriodAverage none;
  EXPECT_EQ(none.period_samples(), 0.0);
  EXPECT_EQ(none.step(1.5), 1.5);
  EXPECT_EQ(hc::PeriodAverage(0.5).step(-3.0), -3.0);
  EXPECT_THROW(hc::PeriodAverage(-1.0), std::invalid_argument);
  EXPECT_THROW(hc::PeriodAverage(std::nan("")), std::invalid_argument);
}
