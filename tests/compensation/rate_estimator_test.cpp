// The rate the rate-dependent models see: a filtered |du/dt| that follows a ramp, lets a step
// decay instead of spiking for one sample, and the largest rate of a record's smooth parts.
#include "hystbench/compensation/rate_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace hc = hystbench::compensation;

TEST(RateEstimator, FollowsARampAndSettlesOnItsRate) {
  hc::RateEstimator e(2e-3, 1e-4);
  e.reset(0.0);
  double rate = 0.0;
  for (int k = 1; k <= 400; ++k) rate = e.step(50.0 * k * 1e-4);  // 50 V/s for 40 ms = 20 tau
  EXPECT_NEAR(rate, 50.0, 1e-6);
  // Falling: the magnitude, not the sign.
  for (int k = 1; k <= 400; ++k) rate = e.step(2.0 - 50.0 * k * 1e-4);
  EXPECT_NEAR(rate, 50.0, 1e-6);
}

TEST(RateEstimator, TheSignedLawKeepsTheDirection) {
  hc::RateEstimator e(2e-3, 1e-4, hc::RateLaw::kSigned);
  e.reset(0.0);
  double rate = 0.0;
  for (int k = 1; k <= 400; ++k) rate = e.step(50.0 * k * 1e-4);
  EXPECT_NEAR(rate, 50.0, 1e-6);
  for (int k = 1; k <= 400; ++k) rate = e.step(2.0 - 50.0 * k * 1e-4);
  EXPECT_NEAR(rate, -50.0, 1e-6);
  EXPECT_DOUBLE_EQ(e.value(), rate);
  EXPECT_NEAR(e.peek(2.0 - 50.0 * 401 * 1e-4), rate, 1e-6);
  EXPECT_EQ(hc::estimate_rates(std::vector<double>{1.0, 0.5}, 1e-3, 0.0, hc::RateLaw::kSigned)[1],
            -500.0);
}

TEST(RateEstimator, PeekDoesNotChangeTheStateAndZeroTauIsThePerSampleDifference) {
  hc::RateEstimator e(0.0, 1e-3);
  e.reset(1.0);
  EXPECT_DOUBLE_EQ(e.peek(1.5), 500.0);
  EXPECT_DOUBLE_EQ(e.value(), 0.0);
  EXPECT_DOUBLE_EQ(e.step(1.5), 500.0);
  EXPECT_DOUBLE_EQ(e.step(1.5), 0.0);
}

TEST(RateEstimator, AStepDecaysInsteadOfSpikingForOneSample) {
  const double dt = 1e-4, tau = 1e-3;
  hc::RateEstimator e(tau, dt);
  e.reset(0.0);
  const double first = e.step(10.0);  // a 10 V step: 1e5 V/s for one sample unfiltered
  EXPECT_LT(first, 0.1 * 10.0 / dt);
  double after = first;
  for (int k = 0; k < 50; ++k) after = e.step(10.0);  // 5 tau later
  EXPECT_LT(after, 0.01 * first);
}

TEST(SmoothMaxRate, IgnoresStepsButKeepsTheFastestSmoothPart) {
  const double dt = 1e-3;
  std::vector<double> u;
  // A 2 Hz sine of amplitude 10 (peak rate 2 pi 2 10 = 125.7/s), then a hold, a 50-unit step and
  // another hold.
  for (int k = 0; k < 1000; ++k)
    u.push_back(10.0 * std::sin(2.0 * std::numbers::pi * 2.0 * k * dt));
  for (int k = 0; k < 100; ++k) u.push_back(0.0);
  for (int k = 0; k < 100; ++k) u.push_back(50.0);
  const double peak = 2.0 * std::numbers::pi * 2.0 * 10.0;
  const double got = hc::smooth_max_rate(u, dt);
  EXPECT_NEAR(got, peak, 0.01 * peak);
  // The step alone is not smooth.
  std::vector<double> step(20, 0.0);
  step.insert(step.end(), 20, 5.0);
  EXPECT_EQ(hc::smooth_max_rate(step, dt), 0.0);
}
