// SimulatedActuator::step()/reset(), SimulatedStage::step()/reset() and SignalGenerator::value()
// must not allocate: this file counts the allocations of the test thread
// (support/allocation_counter.hpp).
#include <gtest/gtest.h>

#include "hystbench/sim/signal_generator.hpp"
#include "hystbench/sim/simulated_actuator.hpp"
#include "hystbench/sim/simulated_stage.hpp"
#include "support/allocation_counter.hpp"
#include "support/every_effect_on.hpp"

using hystbench::test::allocations_during;

namespace hs = hystbench::sim;

TEST(RealTimeSafety, ActuatorStepAndResetDoNotAllocateWithEveryEffectOn) {
  hs::SimulatedActuator a(hystbench::testing::every_effect_on(), 1e-4);
  double sink = 0.0;
  const long n = allocations_during([&] {
    for (int k = 0; k < 20000; ++k) sink += a.step(75.0 + 70.0 * std::sin(k * 1e-3));
    a.reset(20.0);
    sink += a.step(30.0);
  });
  EXPECT_EQ(n, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

TEST(RealTimeSafety, StageStepAndResetDoNotAllocateWithSixCoupledAxes) {
  hs::SimulatedStageConfig c;
  for (int i = 0; i < 6; ++i)
    c.axes.push_back({"a" + std::to_string(i), hystbench::testing::every_effect_on()});
  c.coupling.gains.assign(6, std::vector<double>(6, 0.05));
  for (int i = 0; i < 6; ++i) c.coupling.gains[i][i] = 0.0;
  hs::SimulatedStage stage(c, 1e-4);
  double u[6], y[6];
  double sink = 0.0;
  const long n = allocations_during([&] {
    for (int k = 0; k < 5000; ++k) {
      for (int i = 0; i < 6; ++i) u[i] = 75.0 + 70.0 * std::sin(k * 1e-3 * (i + 1));
      stage.step(u, y);
      sink += y[k % 6];
    }
    stage.reset(u);
  });
  EXPECT_EQ(n, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

TEST(RealTimeSafety, SignalValuesDoNotAllocate) {
  for (const char* name : {"sine", "decaying_sine", "triangle", "sawtooth", "steps",
                           "multi_frequency", "chirp", "csv"}) {
    hs::SignalSpec s;
    s.kind = hs::signal_kind_from_string(name);
    s.duration_s = 10.0;
    s.steps = {{0.0, 1.0}, {1.0, 2.0}};
    s.samples = {{0.0, 0.0}, {1.0, 1.0}, {5.0, -1.0}};
    const auto g = hs::make_signal_generator(s);
    double sink = 0.0;
    EXPECT_EQ(allocations_during([&] {
                for (int k = 0; k < 1000; ++k) sink += g->value(k * 0.013);
              }),
              0)
        << name;
    EXPECT_TRUE(std::isfinite(sink));
  }
}
