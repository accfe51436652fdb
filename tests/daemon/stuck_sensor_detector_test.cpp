#include "hystbench/daemon/stuck_sensor_detector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace hd = hystbench::daemon;

namespace {

/// Feeds a ramp of the output with a frozen reading; returns the tick that reported, or -1.
int ticks_until_detected(hd::StuckSensorDetector& d, double u0, double du, int n, double y) {
  for (int k = 0; k < n; ++k) {
    if (d.update(u0 + du * k, y)) return k;
  }
  return -1;
}

}  // namespace

TEST(StuckSensorDetector, FrozenReadingWhileTheOutputSweepsIsFoundAfterTheWindow) {
  hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
  // 0.5 V per tick: the span is reached after 6 repeats, the window after 20.
  EXPECT_EQ(ticks_until_detected(d, 10.0, 0.5, 100, 7.25), 20);
}

TEST(StuckSensorDetector, FrozenReadingAtAConstantOutputIsNotAFault) {
  // A held output and a noise-free sensor repeat the same value legitimately.
  hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
  EXPECT_EQ(ticks_until_detected(d, 50.0, 0.0, 10000, 7.25), -1);
  // Creeping output, still within the span: not a fault either.
  d.reset();
  EXPECT_EQ(ticks_until_detected(d, 50.0, 2.9 / 10000, 10000, 7.25), -1);
}

TEST(StuckSensorDetector, SlowSweepIsFoundOnceTheSpanIsCovered) {
  hd::StuckSensorDetector d({.ticks = 20, .output_span_v = 3.0});
  // 0.01 V per tick: the window passes first, the span is covered at repeat 300.
  EXPECT_EQ(ticks_until_detected(d, 0.0, 0.01, 1000, 1.0), 300);
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
  // One repeat short of the window, then a change: no report; the new value starts over.
  d.reset();
  EXPECT_EQ(ticks_until_detected(d, 0.0, 1.0, 20, 2.0), -1);
  EXPECT_EQ(ticks_until_detected(d, 20.0, 1.0, 20, 2.0 + 1e-12), -1);
  EXPECT_EQ(ticks_until_detected(d, 40.0, 1.0, 21, 2.0 + 1e-12), 0);
}

TEST(StuckSensorDetector, ZeroTicksIsOff) {
  hd::StuckSensorDetector d({.ticks = 0, .output_span_v = 3.0});
  EXPECT_EQ(ticks_until_detected(d, 0.0, 10.0, 1000, 1.0), -1);
}
