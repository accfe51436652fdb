#include "hystbench/compensation/loop_analysis.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace hc = hystbench::compensation;

namespace {

constexpr double kPi = std::numbers::pi;

// A gain g behind d whole samples, measured on log-spaced lines up to 0.45 of the rate.
hc::MeasuredResponse delayed_gain(double g, int d, double dt) {
  hc::MeasuredResponse r;
  for (double f = 1.0; f < 0.45 / dt; f *= 1.02) {
    r.frequency_hz.push_back(f);
    r.response.push_back(g * std::polar(1.0, -2.0 * kPi * f * dt * d));
    r.noise.push_back(0.0);
    r.coherence.push_back(1.0);
  }
  r.label = "gain and delay";
  return r;
}

hc::FeedbackController integral(double ki, double dt) {
  hc::FeedbackLaw law;
  law.pid.ki = ki;
  return hc::FeedbackController(law, dt);
}

}  // namespace

// L = ki T / (1 - 1/z) z^-(1+d) g: at theta = w T, |L| = ki T g / (2 sin(theta / 2)) and
// arg L = theta / 2 - pi / 2 - theta (1 + d). So the crossover is at 2 asin(ki T g / 2), the
// phase margin pi / 2 - theta_c (d + 1/2), the phase crossover at pi / (2 d + 1) and the gain
// margin 2 sin(theta_180 / 2) / (ki T g).
TEST(LoopMargins, MatchTheAnalyticMarginsOfAnIntegralLoopBehindADelay) {
  const double dt = 1e-4, g = 0.9;
  for (const int d : {0, 1, 3}) {
    for (const double ki : {300.0, 1500.0, 4000.0}) {
      const hc::MeasuredResponse p = delayed_gain(g, d, dt);
      const hc::LoopMargins m = hc::loop_margins(p, integral(ki, dt), dt);
      const double k = ki * dt * g;
      const double theta_c = 2.0 * std::asin(k / 2.0);
      const double pm = (kPi / 2.0 - theta_c * (d + 0.5)) * 180.0 / kPi;
      const double theta_180 = kPi / (2.0 * d + 1.0);
      const double gm = 20.0 * std::log10(2.0 * std::sin(theta_180 / 2.0) / k);
      SCOPED_TRACE("d " + std::to_string(d) + ", ki " + std::to_string(ki));
      EXPECT_NEAR(m.crossover_hz, theta_c / (2.0 * kPi * dt), 0.005 * m.crossover_hz);
      EXPECT_NEAR(m.phase_margin_deg, pm, 0.5);
      if (theta_180 < 2.0 * kPi * 0.45) {  // within the measured band
        EXPECT_NEAR(m.gain_margin_db, gm, 0.1);
        EXPECT_NEAR(m.gain_margin_hz, theta_180 / (2.0 * kPi * dt), 0.01 * m.gain_margin_hz);
      }
      EXPECT_EQ(m.stable, gm > 0.0);
    }
  }
}

TEST(LoopMargins, CountTheUnstablePolesOfALoopBeyondItsGainMargin) {
  const double dt = 1e-4;
  const hc::MeasuredResponse p = delayed_gain(1.0, 2, dt);
  // Phase crossover at pi / 5; the gain margin is 2 sin(pi / 10) / (ki dt): 0 dB at ki 6180.
  EXPECT_TRUE(hc::loop_margins(p, integral(5500.0, dt), dt).stable);
  const hc::LoopMargins m = hc::loop_margins(p, integral(7000.0, dt), dt);
  EXPECT_FALSE(m.stable);
  EXPECT_EQ(m.unstable_poles, 2);
  EXPECT_LT(m.gain_margin_db, 0.0);
}

TEST(LoopMargins, GiveTheClosedLoopBandwidthAndThePeakSensitivity) {
  const double dt = 1e-4;
  const hc::MeasuredResponse p = delayed_gain(1.0, 0, dt);
  // A slow integral loop is a first-order closed loop: T = 1 / (1 + s / ki), -3 dB at ki,
  // |S| peaking at 1 (0 dB) only as the frequency grows.
  const double ki = 2.0 * kPi * 50.0;
  const hc::LoopMargins m = hc::loop_margins(p, integral(ki, dt), dt);
  EXPECT_NEAR(m.bandwidth_hz, 50.0, 1.0);
  EXPECT_NEAR(m.crossover_hz, 50.0, 1.0);
  EXPECT_LT(m.peak_sensitivity_db, 0.5);
  EXPECT_GT(m.phase_margin_deg, 85.0);
  EXPECT_TRUE(hc::meets(m, {}));
}
