#include "hystbench/daemon/loop/stuck_sensor_detector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace hd = hystbench::daemon;

namespace {

/// Feeds a ramp of the output with a frozen reading; returns the tick that reported, or -1.
int ticks_until_detected(hd::StuckSensorDetector& d, double u0, double du, int n, double y,
                         std::uint64_t response_ticks = 0) {
  for (int k = 0; k < n; ++k) {
    if (d.update(u0 + du * k, y, response_ticks)) return k;
  }
  return -1;
}

/// A noise-free sensor behind a pure delay: the output holds at u_hold for `hold` ticks, then
/// steps to u_step; the reading (gain 0.3 um/V) follows `delay` ticks late, reported as each
/// reading's response_ticks when `report` is set. Returns the tick that reported, or -1.
int hold_then_step(hd::StuckSensorDetector& d, int hold, int delay, bool report) {
  const double u_hold = 75.0, u_step = 150.0;
  for (int k = 0; k < hold + 200; ++k) {
    const double u = k < hold ? u_hold : u_step;
    const double y = 0.3 * (k < hold + delay ? u_hold : u_step);
    if (d.update(u, y, report ? static_cast<std::uint64_t>(delay) : 0)) return k;
  }
  return -1;
}

}  // namespace

TEST(StuckSensorDetector, FrozenReadingIsFoundTheWindowAfterTheOutputHasMovedTheSpan) {
  hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
  // 0.5 V per tick: the output is 3 V away at tick 6, the window of 20 readings follows.
  EXPECT_EQ(ticks_until_detected(d, 10.0, 0.5, 100, 7.25), 6 + 20);
  // Each reading answering the output of 2 ticks before: found 2 ticks later.
  d.reset();
  EXPECT_EQ(ticks_until_detected(d, 10.0, 0.5, 100, 7.25, 2), 6 + 20 + 2);
}

TEST(StuckSensorDetector, FrozenReadingAtAConstantOutputIsNotAFault) {
  // A held output and a noise-free sensor repeat the same value legitimately.
  hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
  EXPECT_EQ(ticks_until_detected(d, 50.0, 0.0, 10000, 7.25), -1);
  // Creeping output, still within the span: not a fault either.
  d.reset();
  EXPECT_EQ(ticks_until_detected(d, 50.0, 2.9 / 10000, 10000, 7.25), -1);
}

TEST(StuckSensorDetector, SlowSweepIsFoundTheWindowAfterTheSpanIsCovered) {
  hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
  // 0.01 V per tick: 3 V away at tick 300.
  EXPECT_EQ(ticks_until_detected(d, 0.0, 0.01, 1000, 1.0), 300 + 20);
}

TEST(StuckSensorDetector, ANoiseFreeSensorHeldThenSteppedIsNotAFault) {
  // The case: the output holds longer than the window (the reading repeats, rightly),
  // then steps; the reading answers one or two ticks later (a thread-mode Modbus exchange).
  for (const int delay : {0, 1, 2, 5}) {
    hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
    EXPECT_EQ(hold_then_step(d, 1000, delay, true), -1) << "delay " << delay;
    d.reset();
    EXPECT_EQ(hold_then_step(d, 1000, delay, false), -1) << "unreported delay " << delay;
  }
}

TEST(StuckSensorDetector, AResponseLaterThanTheWindowNeedsItsLatencyKnown) {
  // The answer comes 25 ticks after the step, beyond the 20-tick window.
  hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
  EXPECT_EQ(hold_then_step(d, 500, 25, false), 500 + 20);  // latency unknown: faulted
  d.reset();
  EXPECT_EQ(hold_then_step(d, 500, 25, true), -1);  // each reading reports it
  d.reset(10);                                      // an identified 10-tick model delay
  EXPECT_EQ(hold_then_step(d, 500, 25, false), -1);
}

TEST(StuckSensorDetector, AFrozenReadingAfterAHoldIsFoundAfterTheStep) {
  hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
  // The reading never answers the step: found the window plus the response after it.
  int k = 0;
  for (; k < 1000; ++k) ASSERT_FALSE(d.update(75.0, 22.5, 1));
  int found = -1;
  for (; k < 1200 && found < 0; ++k) {
    if (d.update(150.0, 22.5, 1)) found = k;
  }
  EXPECT_EQ(found, 1000 + 20 + 1);
}

TEST(StuckSensorDetector, ASlowDeviceIsJudgedInTicksAtItsFreshReadings) {
  // A fresh reading every 25 ticks, each answering the output of 25 ticks before it; the
  // output holds, then steps at tick 500 and holds again.
  const auto run = [](hd::StuckSensorDetector& d, bool frozen) {
    for (int k = 0; k < 1000; ++k) {
      const double u = k < 500 ? 75.0 : 150.0;
      if (k % 25 != 0) {
        d.stale(u);
        continue;
      }
      const double answered = k - 25 < 500 ? 75.0 : 150.0;
      if (d.update(u, 0.3 * (frozen ? 75.0 : answered), 25)) return k;
    }
    return -1;
  };
  hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
  EXPECT_EQ(run(d, false), -1);
  // Frozen: the first fresh reading at least 20 + 25 ticks after the step.
  d.reset();
  EXPECT_EQ(run(d, true), 550);
}

TEST(StuckSensorDetector, ACoarseSensorNeedsTwoCountsOfMovement) {
  // 1 um counts, 0.3 um/V on average; after a reversal the actuator moves at 0.2 um/V, so the
  // reading changes every 5 V of output. A 3 V span would call it stuck; two counts (6.7 V)
  // do not.
  const auto run = [](hd::StuckSensorDetector& d) {
    for (int k = 0; k < 20000; ++k) {
      const double u = 0.01 * k;
      if (d.update(u, std::floor(0.2 * u), 0)) return k;
    }
    return -1;
  };
  hd::StuckSensorDetector span_only({.ticks = 20, .output_span_v = 3.0});
  EXPECT_EQ(run(span_only), 300 + 20);
  hd::StuckSensorDetector with_counts(
      {.ticks = 20, .output_span_v = 3.0, .resolution_um = 1.0, .gain_um_per_v = 0.3});
  EXPECT_NEAR(with_counts.effective_span_v(), 2.0 / 0.3, 1e-12);
  EXPECT_EQ(run(with_counts), -1);
  // A fine sensor keeps the configured span.
  hd::StuckSensorDetector fine(
      {.ticks = 20, .output_span_v = 3.0, .resolution_um = 0.001, .gain_um_per_v = 0.3});
  EXPECT_EQ(fine.effective_span_v(), 3.0);
}

TEST(StuckSensorDetector, AnyChangeOfTheReadingRestartsTheWindow) {
  hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-3);
  // A live sensor: the output sweeps 150 V back and forth, the reading follows with noise.
  for (int k = 0; k < 200000; ++k) {
    const double u = 75.0 + 75.0 * std::sin(2e-3 * k);
    ASSERT_FALSE(d.update(u, 0.3 * u + noise(rng))) << "tick " << k;
  }
  // Moved at tick 3, one reading short of the window, then a change: no report; the new value
  // starts over from its own output.
  d.reset();
  EXPECT_EQ(ticks_until_detected(d, 0.0, 1.0, 23, 2.0), -1);
  EXPECT_EQ(ticks_until_detected(d, 23.0, 1.0, 23, 2.0 + 1e-12), -1);
  EXPECT_EQ(ticks_until_detected(d, 46.0, 1.0, 24, 2.0 + 1e-12), 0);
}

TEST(StuckSensorDetector, ZeroTicksIsOff) {
  hd::StuckSensorDetector d({.ticks = 0, .output_span_v = 3.0});
  EXPECT_EQ(ticks_until_detected(d, 0.0, 10.0, 1000, 1.0), -1);
}
