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

// The incremental law summed up is the positional PID
//   u_k = kp (e_k - e_0) + ki dt sum_{i<=k} e_i + kd (ef_k - ef_{k-1}) / dt,
// with ef the error through the derivative's first-order low-pass (ef_{-1} = ef_0 = e_0): every
// term, the derivative's included, checked on an error that ramps, jumps and oscillates.
TEST(PidController, MatchesThePositionalPidWithEveryTerm) {
  const double dt = 1e-3;
  for (const double filter_hz : {0.0, 50.0}) {
    const hc::PidParameters p{0.4, 30.0, 2e-3, filter_hz, -1e9, 1e9};
    hc::PidController pid(p, dt);
    const double alpha =
        filter_hz > 0.0 ? dt / (1.0 / (2.0 * std::acos(-1.0) * filter_hz) + dt) : 1.0;
    double sum = 0.0, e0 = 0.0, ef = 0.0, ef_prev = 0.0;
    for (int k = 0; k < 400; ++k) {
      const double e = (k < 100 ? 0.02 * k : 3.0) + (k >= 200 ? std::sin(0.3 * k) : 0.0);
      if (k == 0) {
        e0 = ef = ef_prev = e;
      } else {
        ef_prev = ef;
        ef += alpha * (e - ef);
      }
      sum += e;
      const double expected = p.kp * (e - e0) + p.ki * dt * sum + p.kd * (ef - ef_prev) / dt;
      ASSERT_NEAR(pid.step(e), expected, 1e-9 * (1.0 + std::abs(expected)))
          << "sample " << k << ", derivative filter " << filter_hz << " Hz";
    }
  }
}

// A step of the error kicks the derivative term by kd / dt once (unfiltered), or by
// kd alpha (1 - alpha)^(k-1) / dt decaying (filtered): the rate of the error, not its size.
TEST(PidController, DerivativeActsOnTheErrorsRate) {
  const double dt = 1e-3, kd = 1e-3;
  hc::PidController pid({0.0, 0.0, kd, 0.0, -1e9, 1e9}, dt);
  EXPECT_DOUBLE_EQ(pid.step(0.0), 0.0);
  EXPECT_NEAR(pid.step(1.0), kd / dt, 1e-12);  // the kick
  EXPECT_NEAR(pid.step(1.0), 0.0, 1e-12);      // a constant error has no rate
  EXPECT_NEAR(pid.step(3.0), 2.0 * kd / dt, 1e-12);

  const double hz = 20.0;
  const double alpha = dt / (1.0 / (2.0 * std::acos(-1.0) * hz) + dt);
  hc::PidController filtered({0.0, 0.0, kd, hz, -1e9, 1e9}, dt);
  filtered.step(0.0);
  for (int k = 1; k < 50; ++k) {
    EXPECT_NEAR(filtered.step(1.0), kd / dt * alpha * std::pow(1.0 - alpha, k - 1), 1e-12)
        << "sample " << k;
  }
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
