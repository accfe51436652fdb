#include "hystbench/compensation/pid_controller.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hc = hystbench::compensation;

namespace {
// First-order plant y' = (g u - y) / tau, exact discretisation.
struct Plant {
  double y = 0.0, a, g;
  Plant(double tau, double gain, double dt) : a(std::exp(-dt / tau)), g(gain) {}
  double step(double u) { return y = a * y + (1.0 - a) * g * u; }
};
}  // namespace

TEST(PidController, IntegralActionRemovesSteadyStateError) {
  const double dt = 1e-3;
  hc::PidController pid({0.5, 20.0, 0.0, 0.0, -100.0, 100.0}, dt);
  Plant plant(0.01, 0.3, dt);
  double y = 0.0;
  for (int k = 0; k < 5000; ++k) y = plant.step(pid.step(10.0 - y));
  EXPECT_NEAR(y, 10.0, 1e-6);
}

TEST(PidController, ProportionalOnlyLeavesAnOffset) {
  const double dt = 1e-3;
  hc::PidController pid({0.5, 0.0, 0.0, 0.0, -100.0, 100.0}, dt);
  Plant plant(0.01, 0.3, dt);
  double y = 0.0;
  for (int k = 0; k < 5000; ++k) y = plant.step(pid.step(10.0 - y));
  // Incremental P is Kp * e relative to the starting error, so the output integrates nothing.
  EXPECT_GT(std::abs(10.0 - y), 1.0);
}

TEST(PidController, ClampsAndDoesNotWindUp) {
  const double dt = 1e-3;
  hc::PidController pid({0.1, 50.0, 0.0, 0.0, -5.0, 5.0}, dt);
  Plant plant(0.01, 0.3, dt);
  double y = 0.0;
  // Unreachable target for 2 s: output pinned at the clamp, never beyond.
  for (int k = 0; k < 2000; ++k) {
    const double u = pid.step(100.0 - y);
    ASSERT_LE(u, 5.0);
    y = plant.step(u);
  }
  EXPECT_DOUBLE_EQ(pid.output(), 5.0);
  // A reachable target: with anti-windup the output leaves the clamp promptly.
  int samples_to_leave = 0;
  while (pid.step(0.5 - y) >= 5.0 && samples_to_leave < 10000) {
    y = plant.step(pid.output());
    ++samples_to_leave;
  }
  EXPECT_LT(samples_to_leave, 50);
}

TEST(PidController, ExternalSaturationStopsIntegration) {
  hc::PidController pid({0.0, 10.0, 0.0, 0.0, -1e9, 1e9}, 1e-3);
  pid.set_saturation(+1);
  for (int k = 0; k < 100; ++k) pid.step(1.0);
  EXPECT_DOUBLE_EQ(pid.output(), 0.0);
  pid.set_saturation(0);
  pid.step(1.0);
  EXPECT_GT(pid.output(), 0.0);
}

TEST(PidController, RejectsBadParameters) {
  EXPECT_THROW(hc::PidController({NAN, 0, 0, 0, -1, 1}, 1e-3), std::invalid_argument);
  EXPECT_THROW(hc::PidController({1, 0, 0, 0, 1, -1}, 1e-3), std::invalid_argument);
  EXPECT_THROW(hc::PidController({1, 0, 0, 0, -1, 1}, 0.0), std::invalid_argument);
}
