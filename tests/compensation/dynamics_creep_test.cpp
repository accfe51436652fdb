#include <gtest/gtest.h>

#include <cmath>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/creep_operator_bank.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/second_order_dynamics.hpp"

namespace hc = hystbench::compensation;

TEST(SecondOrderDynamics, UnitDcGainAndRingsAtTheDampedFrequency) {
  const double fs = 100000.0, fn = 2000.0, zeta = 0.02;
  hc::SecondOrderDynamics dyn({fn, zeta}, 1.0 / fs);
  dyn.reset(0.0);
  std::vector<double> y;
  for (int k = 0; k < 20000; ++k) y.push_back(dyn.step(1.0));
  EXPECT_NEAR(y.back(), 1.0, 1e-6);
  // Count upward crossings of 1.0 over the first 10 ms.
  int crossings = 0;
  for (int k = 1; k < 1000; ++k) crossings += (y[k - 1] < 1.0 && y[k] >= 1.0);
  const double fd = fn * std::sqrt(1.0 - zeta * zeta);
  EXPECT_NEAR(crossings, fd * 0.01, 1.0);
  // Overshoot of a lightly damped system: exp(-pi zeta / sqrt(1 - zeta^2)).
  const double peak = *std::max_element(y.begin(), y.end());
  EXPECT_NEAR(peak - 1.0, std::exp(-M_PI * zeta / std::sqrt(1 - zeta * zeta)), 0.01);
}

TEST(CreepOperatorBank, OutputKeepsMovingDuringAHoldAndSettles) {
  const double dt = 1e-3;
  hc::CreepOperatorBank creep({hc::log_spaced_time_constants(4, 0.01, 10.0), {0.1, 0.1, 0.1, 0.1}},
                              dt);
  creep.reset(0.0);
  std::vector<double> y;
  for (int k = 0; k < 100000; ++k) y.push_back(creep.step(1.0));
  for (std::size_t k = 1; k < y.size(); ++k) ASSERT_GE(y[k], y[k - 1]);
  EXPECT_GT(y[5000] - y[100], 0.05);  // still moving seconds after the step
  EXPECT_NEAR(y.back(), 0.4, 1e-3);
}

TEST(ActuatorModel, AHeldOutputLeavesTheStateItsStepsWould) {
  // A model with every part: a long hold moved in closed form ends where stepping ends.
  const double dt = 1e-3;
  hc::ActuatorModel stepped(
      std::make_unique<hc::PiModel>(hc::PiParameters{{0.0, 1.0}, {0.3, 0.1}, 0}));
  stepped.set_creep(
      hc::CreepParameters{hc::log_spaced_time_constants(4, 0.05, 500.0), {0.01, 0.02, 0.02, 0.05}});
  stepped.set_dynamics(hc::DynamicsParameters{200.0, 0.05});
  stepped.set_delay(0.003);
  stepped.configure(dt);
  stepped.reset(0.0);
  for (int k = 0; k < 2000; ++k) (void)stepped.step(8.0 * std::sin(0.01 * k));
  hc::ActuatorModel held(stepped);
  const std::uint64_t steps = 200000;  // 200 s, 200x the stepped part of hold()
  const double before = held.peek_static(2.0);
  for (std::uint64_t k = 0; k < steps; ++k) (void)stepped.step(2.0);
  held.hold(2.0, steps);
  // The creep moved over the hold by far more than the tolerance below.
  EXPECT_GT(std::abs(held.peek_static(2.0) - before), 1e-3);
  for (const double u : {2.0, 3.0, -1.0}) {
    EXPECT_NEAR(held.step(u), stepped.step(u), 1e-6) << u;  // of an output moving 1e-3 or more
  }
}

TEST(ActuatorModel, AShortHoldIsStepped) {
  hc::ActuatorModel stepped(
      std::make_unique<hc::PiModel>(hc::PiParameters{{0.0, 1.0}, {0.3, 0.1}, 0}));
  stepped.set_creep(hc::CreepParameters{{0.1, 2.0}, {0.02, 0.05}});
  stepped.configure(1e-3);
  stepped.reset(0.0);
  hc::ActuatorModel held(stepped);
  for (int k = 0; k < 300; ++k) (void)stepped.step(4.0);
  held.hold(4.0, 300);
  EXPECT_EQ(held.step(1.0), stepped.step(1.0));
}

TEST(ActuatorModel, DelayShiftsTheOutputByWholeSamples) {
  hc::ActuatorModel plain(
      std::make_unique<hc::PiModel>(hc::PiParameters{{0.0, 1.0}, {0.3, 0.1}, 0}));
  hc::ActuatorModel delayed(plain);
  delayed.set_delay(0.005);
  std::vector<double> u;
  for (int k = 0; k < 1000; ++k) u.push_back(5.0 * std::sin(0.02 * k));
  const auto y0 = plain.simulate(u, 1e-3);
  const auto y5 = delayed.simulate(u, 1e-3);
  EXPECT_EQ(delayed.delay_samples(), 5u);
  for (std::size_t k = 5; k < u.size(); ++k) ASSERT_DOUBLE_EQ(y5[k], y0[k - 5]);
}
