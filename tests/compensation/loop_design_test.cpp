#include "hystbench/compensation/loop_design.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <span>

#include "compensation/measured_stage_support.hpp"

namespace hc = hystbench::compensation;
using hystbench::test::measured;
using hystbench::test::Stage;
using hystbench::test::StageSimulation;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// The closed loop in time: the stage fed back through `law` (the reading answered a tick
// later); returns the largest |e| over the last tenth after a unit step at t = 0, or inf if it
// ran away.
double step_residual(const Stage& s, const hc::FeedbackLaw& law, int ticks) {
  StageSimulation sim(s);
  hc::FeedbackController c(law, s.dt);
  double y = 0.0, tail = 0.0;
  for (int k = 0; k < ticks; ++k) {
    const double u = c.step(1.0 - y);
    y = sim.step(u);
    if (!std::isfinite(y) || std::abs(y) > 1e6) return INFINITY;
    if (k > ticks * 9 / 10) tail = std::max(tail, std::abs(1.0 - y));
  }
  return tail;
}

// |y| / |r| of the closed loop for a sine at f_hz, in steady state.
double closed_loop_gain(const Stage& s, const hc::FeedbackLaw& law, double f_hz) {
  StageSimulation sim(s);
  hc::FeedbackController c(law, s.dt);
  const int per = static_cast<int>(std::lround(1.0 / (f_hz * s.dt)));
  double y = 0.0, peak = 0.0;
  for (int k = 0; k < 60 * per; ++k) {
    const double r = std::sin(kTwoPi * k / per);
    y = sim.step(c.step(r - y));
    if (k >= 40 * per) peak = std::max(peak, std::abs(y));
  }
  return peak;
}

// |r - y| / |r| of the closed loop for a sine at f_hz, in steady state: |S|.
double closed_loop_error(const Stage& s, const hc::FeedbackLaw& law, double f_hz) {
  StageSimulation sim(s);
  hc::FeedbackController c(law, s.dt);
  const int per = static_cast<int>(std::lround(1.0 / (f_hz * s.dt)));
  double y = 0.0, r_prev = 0.0, peak = 0.0;
  for (int k = 0; k < 60 * per; ++k) {
    const double r = std::sin(kTwoPi * k / per);
    // The bench's timing: this tick's drive from the last tick's error.
    y = sim.step(c.step(r_prev - y));
    if (k >= 40 * per) peak = std::max(peak, std::abs(r - y));
    r_prev = r;
  }
  return peak;
}

hc::LoopDesignOptions options(double dt) {
  hc::LoopDesignOptions o;
  o.dt_s = dt;
  return o;
}

}  // namespace

TEST(MeasuredModes, FindTheStagesModeWithItsDamping) {
  const Stage s{1.0, {3000.0, 0.06}, 0, 1e-4};
  const std::vector<hc::MeasuredMode> modes = hc::measured_modes(measured(s));
  ASSERT_FALSE(modes.empty());
  EXPECT_NEAR(modes[0].frequency_hz, 3000.0, 0.03 * 3000.0);
  EXPECT_NEAR(modes[0].damping_ratio, 0.06, 0.02);
  EXPECT_GT(modes[0].peak_db, 15.0);
}

TEST(MeasuredModes, ALinearStageWithoutAModeHasNone) {
  Stage s;
  s.mode = {20000.0, 0.7};  // far above the band: flat
  EXPECT_TRUE(hc::measured_modes(measured(s)).empty());
}

// The loopback's stage (a 3 kHz mode, zeta 0.06, at 10 kHz): every target holds on every
// response, the loop is stable in time with the gain and the mode moved as the design allowed
// for, and the bandwidth it states is the one a sine sees.
TEST(LoopDesign, MeetsTheTargetsOnAKnownStageAndReachesTheBandwidthItStates) {
  const Stage s{1.0, {3000.0, 0.06}, 0, 1e-4};
  const std::vector<hc::MeasuredResponse> r = measured(s);
  const hc::LoopDesign d = hc::design_loop(r, options(s.dt));
  ASSERT_TRUE(d.found) << d.limit;
  EXPECT_TRUE(d.evaluation.ok()) << d.evaluation.failure;
  for (const hc::LoopMargins& m : d.evaluation.margins) {
    EXPECT_GE(m.gain_margin_db, 6.0);
    EXPECT_GE(m.phase_margin_deg, 45.0);
    EXPECT_LE(m.peak_sensitivity_db, 6.0);
  }
  EXPECT_GE(d.evaluation.bandwidth_hz, 300.0) << d.structure;
  EXPECT_GE(d.evaluation.rejection_bandwidth_hz, 150.0) << d.structure;
  // What the design computed on the measured lines is what the loop does in time: |T| and |S|
  // of a sine at lines from 20 Hz to 2 kHz within 0.3 dB, and |S| at -3 dB where it says the
  // rejection ends (within half a decibel).
  const hc::FeedbackController c(d.law, s.dt);
  const hc::MeasuredResponse& p = r.front();
  for (std::size_t i = 0; i < p.size(); i += 20) {
    const double f = p.frequency_hz[i];
    if (f < 20.0 || f > 2000.0) continue;
    const std::complex<double> l =
        c.response(f) * std::polar(1.0, -kTwoPi * f * s.dt) * p.response[i];
    SCOPED_TRACE(f);
    EXPECT_NEAR(20.0 * std::log10(closed_loop_gain(s, d.law, f)),
                20.0 * std::log10(std::abs(l / (1.0 + l))), 0.3);
    EXPECT_NEAR(20.0 * std::log10(closed_loop_error(s, d.law, f)),
                -20.0 * std::log10(std::abs(1.0 + l)), 0.3);
  }
  const double sens = closed_loop_error(s, d.law, d.evaluation.rejection_bandwidth_hz);
  EXPECT_NEAR(20.0 * std::log10(sens), -3.0, 0.5);
  EXPECT_LT(step_residual(s, d.law, 4000), 1e-3);
  for (const double g : {0.7, 1.3}) {
    for (const double f : {0.8, 1.0, 1.2}) {
      Stage moved = s;
      moved.gain = g;
      moved.mode.natural_frequency_hz *= f;
      EXPECT_LT(step_residual(moved, d.law, 8000), 1e-3) << "gain x" << g << ", mode x" << f;
    }
  }
  EXPECT_FALSE(d.limited_by.empty());
  EXPECT_FALSE(d.limit.empty());
}

// A 1 kHz loop with a 190 Hz mode: integral action alone is held to about zeta f_r; the
// design's shaping lifts it past 20 Hz.
TEST(LoopDesign, ReachesTwentyHertzOnAOneKilohertzLoopWithA190HzMode) {
  const Stage s{1.0, {190.0, 0.07}, 0, 1e-3};
  const hc::LoopDesign d = hc::design_loop(measured(s), options(s.dt));
  ASSERT_TRUE(d.found) << d.limit;
  EXPECT_GE(d.evaluation.bandwidth_hz, 20.0) << d.structure;
  EXPECT_LT(step_residual(s, d.law, 3000), 1e-3);
  EXPECT_EQ(d.limited_by.empty(), false);
}

TEST(LoopDesign, ADelayLimitsTheBandwidthAndIsNamed) {
  const Stage s{1.0, {20000.0, 0.7}, 4, 1e-4};  // no mode in the band, 4 samples of delay
  const hc::LoopDesign d = hc::design_loop(measured(s), options(s.dt));
  ASSERT_TRUE(d.found);
  EXPECT_EQ(d.limited_by, "delay") << d.limit;
  EXPECT_LT(step_residual(s, d.law, 4000), 1e-3);
}

TEST(CheckLoop, NamesTheMarginsAGainSetByHandBreaks) {
  const Stage s{1.0, {3000.0, 0.06}, 0, 1e-4};
  const std::vector<hc::MeasuredResponse> r = measured(s);
  hc::FeedbackLaw slow;
  slow.pid.ki = kTwoPi * 20.0;
  EXPECT_TRUE(hc::check_loop(r, slow, options(s.dt)).ok());
  hc::FeedbackLaw fast;
  fast.pid.ki = kTwoPi * 600.0;  // integral alone past 2 zeta f_r: unstable on the mode
  const hc::LoopEvaluation e = hc::check_loop(r, fast, options(s.dt));
  EXPECT_FALSE(e.ok());
  EXPECT_FALSE(e.margins.front().stable);
  EXPECT_EQ(e.failure_kind, "mode") << e.failure;
  EXPECT_TRUE(std::isinf(step_residual(s, fast, 20000)) || step_residual(s, fast, 20000) > 0.1);
}
