// The simulated actuator's effects one at a time: its modified-PI truth, creep, delay, modes,
// the sensor's filter and noise, the converters' grids, saturation, drift, rate dependence,
// reset, and the configuration it refuses.
#include "hystbench/sim/simulated_actuator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include "hystbench/sim/major_loop_metrics.hpp"
#include "support/simulated_actuator_runs.hpp"

namespace hs = hystbench::sim;
using hystbench::testing::every_effect_off;
using hystbench::testing::ramp;
using hystbench::testing::run;
using hystbench::testing::run_held;

namespace {

double rms(const std::vector<double>& x) {
  return std::sqrt(std::inner_product(x.begin(), x.end(), x.begin(), 0.0) / x.size());
}

/// Lag (0..max_lag samples) at which y best correlates with x.
int best_lag(const std::vector<double>& x, const std::vector<double>& y, int max_lag) {
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / x.size();
  const double my = std::accumulate(y.begin(), y.end(), 0.0) / y.size();
  int best = 0;
  double best_c = -1e300;
  for (int lag = 0; lag <= max_lag; ++lag) {
    double c = 0.0;
    for (std::size_t k = lag; k < x.size(); ++k) c += (x[k - lag] - mx) * (y[k] - my);
    if (c > best_c) best_c = c, best = lag;
  }
  return best;
}

/// Input with a sharp auto-correlation: seeded uniform random levels.
std::vector<double> random_input(std::size_t n, double lo, double hi) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> d(lo, hi);
  std::vector<double> u(n);
  for (auto& v : u) v = d(rng);
  return u;
}

}  // namespace

TEST(SimulatedActuator, TheModifiedPiTruthIsItsModel) {
  auto c = hs::SimulatedActuatorConfig::modified_pi_truth();
  c.sensor_noise.enabled = false;
  c.dac.enabled = false;
  c.adc.enabled = false;
  c.delay.enabled = true;
  const double dt = 1e-4;
  hs::SimulatedActuator a(c, dt);
  auto model = hs::make_truth_model(c, dt);
  const auto u = random_input(5000, 0.0, 150.0);
  a.reset(u[0]);
  const auto y_model = model.simulate(u, dt);
  const auto r = run(a, u);
  for (std::size_t k = 0; k < u.size(); ++k) {
    ASSERT_DOUBLE_EQ(r.measured[k], y_model[k]) << "k=" << k;
    ASSERT_DOUBLE_EQ(r.truth[k], y_model[k]) << "k=" << k;
  }
}

TEST(SimulatedActuator, HysteresisDisabledIsTheLinearMapThroughTheSameLoopEnds) {
  auto with = every_effect_off();
  with.hysteresis.enabled = true;
  const auto h = hs::measure_major_loop(with, 1e-3);
  const auto l = hs::measure_major_loop(every_effect_off(), 1e-3);
  EXPECT_GT(h.hysteresis_percent, 10.0);
  EXPECT_NEAR(l.width_at_mid_um, 0.0, 1e-9);
  EXPECT_NEAR(l.range_um, h.range_um, 1e-3 * h.range_um);
  EXPECT_NEAR(l.min_um, h.min_um, 1e-3 * h.range_um);
}

TEST(SimulatedActuator, CreepIsLogarithmicInTimeAfterAStep) {
  const double dt = 1e-3;
  auto c = every_effect_off();
  c.creep.enabled = true;
  hs::SimulatedActuator creeping(c, dt);
  hs::SimulatedActuator plain(every_effect_off(), dt);
  creeping.reset(0.0);
  plain.reset(0.0);
  const double y_rest = creeping.true_position();
  const auto y = run_held(creeping, 100.0, 300000).truth;  // 300 s
  for (std::size_t k = 1; k < y.size(); ++k) ASSERT_GE(y[k], y[k - 1]);
  // The step the static map gives at once, then the vendors' form from it:
  // y(t) = y0 (1 + gamma log10(t / 0.1 s)), the same rise in every decade.
  const auto at = [&](double t) { return y[static_cast<std::size_t>(t / dt) - 1] - y_rest; };
  const double gamma = c.creep.fraction_per_decade;
  const double y0 = y.front() - y_rest;
  for (const double t : {1.0, 10.0, 100.0, 300.0}) {
    EXPECT_NEAR(at(t) / y0 - 1.0, gamma * std::log10(t / 0.1), 0.05 * gamma) << "t = " << t;
  }
  // Unlike a few lags, it has not levelled off: the decade 30..300 s adds as much as 3..30 s.
  EXPECT_NEAR((at(300.0) - at(30.0)) / (at(30.0) - at(3.0)), 1.0, 0.03);

  const auto z = run_held(plain, 100.0, 20000).truth;
  EXPECT_EQ(z.front(), z.back());
}

TEST(SimulatedActuator, TheModifiedPiTruthsCreepIsLagsOfTheInput) {
  const double dt = 1e-3;
  auto c = every_effect_off();
  c.hysteresis = hs::SimulatedActuatorConfig::modified_pi_truth().hysteresis;
  c.hysteresis.enabled = false;
  c.creep = hs::SimulatedActuatorConfig::modified_pi_truth().creep;
  hs::SimulatedActuator creeping(c, dt);
  const auto y = run_held(creeping, 100.0, 400000).truth;
  for (std::size_t k = 1; k < y.size(); ++k) ASSERT_GE(y[k], y[k - 1]);
  EXPECT_GT(y[19999] - y[999], 0.05);  // still moving 1..20 s after the step [µm]
  // Its slowest lag is 50 s: by 400 s it has levelled off.
  EXPECT_LT(y[399999] - y[299999], 0.05 * (y[29999] - y[2999]));
}

TEST(SimulatedActuator, DelayShiftsTheCrossCorrelationPeak) {
  const double dt = 1e-4;
  auto c = every_effect_off();
  c.delay.enabled = true;
  c.delay.delay_s = 2e-3;
  hs::SimulatedActuator delayed(c, dt);
  const auto u = random_input(4000, 0.0, 150.0);
  EXPECT_EQ(best_lag(u, run(delayed, u).measured, 60), 20);

  hs::SimulatedActuator plain(every_effect_off(), dt);
  EXPECT_EQ(best_lag(u, run(plain, u).measured, 60), 0);
}

/// Amplitude and phase [rad] of x at frequency f over whole periods (a single-bin DFT).
std::pair<double, double> bin(const std::vector<double>& x, double f, double dt) {
  double re = 0.0, im = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    re += x[k] * std::cos(2.0 * M_PI * f * k * dt);
    im -= x[k] * std::sin(2.0 * M_PI * f * k * dt);
  }
  return {2.0 * std::hypot(re, im) / x.size(), std::atan2(im, re)};
}

/// Response to a small sine at f [Hz] around 75 V: (true_position, measured) as bins, over the
/// last `periods` of 2 * periods.
struct FrequencyResponse {
  std::pair<double, double> truth, measured, input;
};
FrequencyResponse respond(const hs::SimulatedActuatorConfig& c, double f, double dt) {
  hs::SimulatedActuator a(c, dt);
  a.reset(75.0);
  const auto n = static_cast<std::size_t>(std::lround(40.0 / (f * dt)));  // 40 periods
  std::vector<double> u(n);
  for (std::size_t k = 0; k < n; ++k) u[k] = 75.0 + 10.0 * std::sin(2.0 * M_PI * f * k * dt);
  const auto r = run(a, u);
  const auto tail = [n](const std::vector<double>& x) {
    return std::vector<double>(x.begin() + static_cast<long>(n / 2), x.end());
  };
  return {bin(tail(r.truth), f, dt), bin(tail(r.measured), f, dt), bin(tail(u), f, dt)};
}

TEST(SimulatedActuator, TwoModesShapeTheFrequencyResponse) {
  const double dt = 1e-5;  // 100 kHz: both modes below the Nyquist frequency
  auto c = every_effect_off();
  c.dynamics.enabled = true;
  const double static_gain = respond(c, 100.0, dt).truth.first;
  std::vector<double> gain;
  const std::vector<double> freqs = {1000.0, 2500.0, 3000.0, 3500.0,
                                     5500.0, 7500.0, 8000.0, 8500.0};
  for (const double f : freqs) gain.push_back(respond(c, f, dt).truth.first / static_gain);
  // Peaks at both modes: above their neighbours, and the first well above the static gain.
  EXPECT_GT(gain[2], gain[1]);
  EXPECT_GT(gain[2], gain[3]);
  EXPECT_GT(gain[2], 3.0);
  EXPECT_GT(gain[6], gain[5]);
  EXPECT_GT(gain[6], gain[7]);
  EXPECT_LT(gain[4], gain[6]);  // the antiresonance-side dip between them
  EXPECT_NEAR(gain[0],
              1.0 / (1.0 - std::pow(1000.0 / 3000.0, 2)) * 0.88 +
                  0.12 / (1.0 - std::pow(1000.0 / 8000.0, 2)),
              0.02);

  hs::SimulatedActuator rigid(every_effect_off(), dt);
  rigid.reset(0.0);
  const auto z = run_held(rigid, 75.0, 2000).truth;
  EXPECT_EQ(*std::max_element(z.begin(), z.end()), z.front());
  EXPECT_EQ(z.front(), z.back());
}

TEST(SimulatedActuator, TheSensorSeesThePositionThroughItsLowPass) {
  const double dt = 1e-5;
  auto c = every_effect_off();
  c.sensor_filter.enabled = true;
  const double fc = c.sensor_filter.cutoff_hz, zeta = c.sensor_filter.damping_ratio;
  for (const double f : {500.0, 2000.0, 5000.0}) {
    const auto r = respond(c, f, dt);
    const double x = f / fc;
    const double gain = 1.0 / std::hypot(1.0 - x * x, 2.0 * zeta * x);
    const double phase = -std::atan2(2.0 * zeta * x, 1.0 - x * x);
    // The sample mean it filters attenuates by cos(pi f dt) more: 1.2 % at 5 kHz here.
    EXPECT_NEAR(r.measured.first / r.truth.first, gain, 0.02 * gain) << f << " Hz";
    EXPECT_NEAR(std::remainder(r.measured.second - r.truth.second - phase, 2.0 * M_PI), 0.0, 0.02)
        << f << " Hz";
  }
}

TEST(SimulatedActuator, SensorNoiseHasTheConfiguredRmsAndIsSeeded) {
  auto c = every_effect_off();
  c.sensor_noise.enabled = true;
  c.sensor_noise.rms_um = 0.02;
  hs::SimulatedActuator noisy(c, 1e-4);
  const auto r = run_held(noisy, 75.0, 40000);
  std::vector<double> e(r.measured.size());
  for (std::size_t k = 0; k < e.size(); ++k) e[k] = r.measured[k] - r.truth[k];
  const double mean = std::accumulate(e.begin(), e.end(), 0.0) / e.size();
  EXPECT_NEAR(rms(e), 0.02, 0.02 * 0.03);
  EXPECT_LT(std::abs(mean), 4.0 * 0.02 / std::sqrt(e.size()));

  hs::SimulatedActuator same_seed(c, 1e-4);
  EXPECT_EQ(run_held(same_seed, 75.0, 40000).measured, r.measured);
  c.sensor_noise.seed += 1;
  hs::SimulatedActuator other_seed(c, 1e-4);
  EXPECT_NE(run_held(other_seed, 75.0, 40000).measured, r.measured);

  hs::SimulatedActuator quiet(every_effect_off(), 1e-4);
  const auto q = run_held(quiet, 75.0, 1000);
  EXPECT_EQ(q.measured, q.truth);
}

TEST(SimulatedActuator, AdcPutsTheMeasurementOnItsGrid) {
  auto c = every_effect_off();
  c.adc = {true, 10, -10.0, 60.0};
  const double lsb = 70.0 / 1023.0;
  hs::SimulatedActuator a(c, 1e-3);
  const auto r = run(a, ramp(0.0, 150.0, 5000));
  for (std::size_t k = 0; k < r.measured.size(); ++k) {
    const double code = (r.measured[k] + 10.0) / lsb;
    ASSERT_NEAR(code, std::round(code), 1e-6) << "k=" << k;
    ASSERT_LE(std::abs(r.measured[k] - r.truth[k]), 0.5 * lsb + 1e-12);
  }
  const std::set<double> levels(r.measured.begin(), r.measured.end());
  EXPECT_LT(levels.size(), 1024u);

  hs::SimulatedActuator fine(every_effect_off(), 1e-3);
  const auto f = run(fine, ramp(0.0, 150.0, 5000)).measured;
  EXPECT_EQ(std::set<double>(f.begin(), f.end()).size(), f.size());
}

TEST(SimulatedActuator, DacPutsTheAppliedVoltageOnItsGrid) {
  auto c = every_effect_off();
  c.dac = {true, 8, 0.0, 150.0};
  const double lsb = 150.0 / 255.0;
  hs::SimulatedActuator a(c, 1e-3);
  std::set<double> positions;
  for (const double u : ramp(0.0, 150.0, 10000)) {
    a.step(u);
    const double code = a.applied_input() / lsb;
    ASSERT_NEAR(code, std::round(code), 1e-9);
    ASSERT_LE(std::abs(a.applied_input() - u), 0.5 * lsb + 1e-12);
    positions.insert(a.true_position());
  }
  EXPECT_LE(positions.size(), 256u);

  hs::SimulatedActuator fine(every_effect_off(), 1e-3);
  fine.step(1.234567);
  EXPECT_EQ(fine.applied_input(), 1.234567);
}

TEST(SimulatedActuator, InputSaturationClampsToTheAmplifierRange) {
  auto c = every_effect_off();
  c.input_saturation.enabled = true;
  hs::SimulatedActuator clamped(c, 1e-3);
  hs::SimulatedActuator reference(c, 1e-3);
  clamped.step(200.0);
  reference.step(150.0);
  EXPECT_EQ(clamped.applied_input(), 150.0);
  EXPECT_EQ(clamped.true_position(), reference.true_position());
  clamped.step(-30.0);
  EXPECT_EQ(clamped.applied_input(), 0.0);

  hs::SimulatedActuator open(every_effect_off(), 1e-3);
  open.step(200.0);
  EXPECT_EQ(open.applied_input(), 200.0);
  EXPECT_GT(open.true_position(), reference.true_position());
}

TEST(SimulatedActuator, DisplacementSaturationClampsTheTruePosition) {
  auto c = every_effect_off();
  c.displacement_saturation = {true, 5.0, 30.0};
  hs::SimulatedActuator stopped(c, 1e-3);
  const auto r = run(stopped, ramp(0.0, 150.0, 1000));
  EXPECT_EQ(*std::max_element(r.truth.begin(), r.truth.end()), 30.0);
  EXPECT_EQ(*std::min_element(r.truth.begin(), r.truth.end()), 5.0);
  EXPECT_EQ(r.measured, r.truth);

  hs::SimulatedActuator free(every_effect_off(), 1e-3);
  const auto f = run(free, ramp(0.0, 150.0, 1000)).truth;
  EXPECT_GT(*std::max_element(f.begin(), f.end()), 40.0);
}

TEST(SimulatedActuator, SinusoidalDriftMovesTheHeldOutputSlowly) {
  const double dt = 1e-2;
  auto c = every_effect_off();
  c.thermal_drift.enabled = true;
  c.thermal_drift.shape = hs::DriftShape::kSinusoid;
  c.thermal_drift.amplitude_um = 0.5;
  c.thermal_drift.period_s = 40.0;
  hs::SimulatedActuator drifting(c, dt);
  const auto y = run_held(drifting, 75.0, 1000).truth;  // a quarter period
  EXPECT_NEAR(y.back() - y.front(), 0.5, 0.01);
  double largest_step = 0.0;
  for (std::size_t k = 1; k < y.size(); ++k) largest_step = std::max(largest_step, y[k] - y[k - 1]);
  EXPECT_LE(largest_step, 2.0 * M_PI * 0.5 / 40.0 * dt * 1.001);

  hs::SimulatedActuator steady(every_effect_off(), dt);
  const auto z = run_held(steady, 75.0, 1000).truth;
  EXPECT_EQ(z.front(), z.back());
}

TEST(SimulatedActuator, RandomWalkDriftWandersWithinItsLimit) {
  const double dt = 1e-2;
  auto c = every_effect_off();
  c.thermal_drift.enabled = true;
  c.thermal_drift.shape = hs::DriftShape::kRandomWalk;
  c.thermal_drift.random_walk_um_per_sqrt_s = 0.05;
  c.thermal_drift.random_walk_limit_um = 0.3;
  hs::SimulatedActuator drifting(c, dt);
  hs::SimulatedActuator steady(every_effect_off(), dt);
  const auto y = run_held(drifting, 75.0, 60000).truth;  // 10 min
  const double base = run_held(steady, 75.0, 1).truth.front();
  std::vector<double> increments;
  double farthest = 0.0;
  for (std::size_t k = 1; k < y.size(); ++k) {
    farthest = std::max(farthest, std::abs(y[k] - base));
    if (std::abs(y[k] - base) < 0.3 - 1e-9 && std::abs(y[k - 1] - base) < 0.3 - 1e-9) {
      increments.push_back(y[k] - y[k - 1]);
    }
  }
  EXPECT_LE(farthest, 0.3 + 1e-9);
  EXPECT_GT(farthest, 0.1);
  EXPECT_NEAR(rms(increments), 0.05 * std::sqrt(dt), 0.05 * std::sqrt(dt) * 0.05);
}

TEST(SimulatedActuator, RateDependenceWidensTheLoopWithTheSquareRootOfTheRate) {
  auto c = every_effect_off();
  c.hysteresis.enabled = true;
  c.rate_dependence.enabled = true;
  const auto quasi_static = hs::measure_major_loop(c, 1e-4, 0.01).width_at_mid_um;
  const auto slow = hs::measure_major_loop(c, 1e-4, 1.0).width_at_mid_um;
  const auto fast = hs::measure_major_loop(c, 1e-4, 16.0).width_at_mid_um;
  EXPECT_GT(fast, 1.15 * slow);
  // Sixteen times the rate: a lag linear in the rate (a delay, a linear filter, weights or
  // thresholds linear in du/dt) would widen the loop about sixteen times as much; the switching
  // front's lag grows four times.
  const double ratio = (fast - quasi_static) / (slow - quasi_static);
  EXPECT_GT(ratio, 3.0);
  EXPECT_LT(ratio, 5.5);
  // The widening, as docs/simulator.md quotes it.
  std::printf("hysteresis of the full-range loop with the switching front:");
  for (const double f : {1.0, 5.0, 10.0, 19.0, 50.0, 100.0}) {
    std::printf(" %g Hz %.1f %%", f, hs::measure_major_loop(c, 1e-4, f).hysteresis_percent);
  }
  std::printf("\n");

  c.rate_dependence.enabled = false;
  const auto slow_ri = hs::measure_major_loop(c, 1e-4, 1.0);
  const auto fast_ri = hs::measure_major_loop(c, 1e-4, 16.0);
  EXPECT_NEAR(fast_ri.width_at_mid_um, slow_ri.width_at_mid_um, 0.01 * slow_ri.width_at_mid_um);
}

// Thresholds that widen with |du/dt|: the loop widens in proportion to the rate (sixteen times
// the rate, about sixteen times the widening), and its tips stay where the input reverses.
TEST(SimulatedActuator, WideningThresholdsWidenTheLoopInProportionToTheRate) {
  auto c = every_effect_off();
  c.hysteresis.enabled = true;
  c.rate_dependence.enabled = true;
  c.rate_dependence.mechanism = hs::RateMechanism::kSwitchingThresholds;
  const auto quasi_static = hs::measure_major_loop(c, 1e-4, 0.01);
  const auto slow = hs::measure_major_loop(c, 1e-4, 1.0);
  const auto fast = hs::measure_major_loop(c, 1e-4, 16.0);
  const double ratio = (fast.width_at_mid_um - quasi_static.width_at_mid_um) /
                       (slow.width_at_mid_um - quasi_static.width_at_mid_um);
  EXPECT_GT(ratio, 10.0);
  EXPECT_LT(ratio, 20.0);
  // The loop's ends: where the input turns, whatever the rate.
  EXPECT_NEAR(fast.max_um, quasi_static.max_um, 1e-3 * quasi_static.range_um);
  EXPECT_NEAR(fast.min_um, quasi_static.min_um, 1e-3 * quasi_static.range_um);
  std::printf("hysteresis of the full-range loop with widening thresholds:");
  for (const double f : {1.0, 5.0, 10.0, 19.0, 50.0, 100.0}) {
    std::printf(" %g Hz %.1f %%", f, hs::measure_major_loop(c, 1e-4, f).hysteresis_percent);
  }
  std::printf("\n");
}

TEST(SimulatedActuator, ThePlayWeightLawWidensTheModifiedPiTruthsLoop) {
  auto c = hs::SimulatedActuatorConfig::modified_pi_truth();
  c.creep.enabled = false;
  c.dynamics.enabled = false;
  c.sensor_noise.enabled = false;
  c.rate_dependence.enabled = true;
  const auto slow = hs::measure_major_loop(c, 1e-4, 1.0);
  const auto fast = hs::measure_major_loop(c, 1e-4, 10.0);
  EXPECT_GT(fast.width_at_mid_um, 1.2 * slow.width_at_mid_um);
}

TEST(SimulatedActuator, ResetRepeatsARunExactly) {
  hs::SimulatedActuatorConfig c;
  c.thermal_drift.enabled = true;
  c.thermal_drift.shape = hs::DriftShape::kRandomWalk;
  hs::SimulatedActuator a(c, 1e-4);
  const auto u = random_input(3000, 0.0, 150.0);
  a.reset(10.0);
  const auto first = run(a, u);
  a.reset(10.0);
  const auto second = run(a, u);
  EXPECT_EQ(first.measured, second.measured);
  EXPECT_EQ(first.truth, second.truth);
}

TEST(SimulatedActuator, ResetSettlesAtTheInput) {
  auto c = every_effect_off();
  c.hysteresis.enabled = true;
  c.creep.enabled = true;
  c.dynamics.enabled = true;
  hs::SimulatedActuator a(c, 1e-4);
  a.reset(90.0);
  const double settled = a.true_position();
  EXPECT_EQ(a.applied_input(), 90.0);
  const auto y = run_held(a, 90.0, 100).truth;
  for (const double v : y) ASSERT_NEAR(v, settled, 1e-9);
}

TEST(SimulatedActuator, NonFiniteInputHoldsThePreviousInput) {
  hs::SimulatedActuator a(every_effect_off(), 1e-3);
  a.step(42.0);
  const double before = a.true_position();
  a.step(std::nan(""));
  EXPECT_EQ(a.applied_input(), 42.0);
  EXPECT_EQ(a.true_position(), before);
  a.step(INFINITY);
  EXPECT_EQ(a.applied_input(), 42.0);
}

TEST(SimulatedActuator, ReportsItsInputRangeAndConfig) {
  auto c = every_effect_off();
  c.input = {-20.0, 120.0};
  hs::SimulatedActuator a(c, 1e-3);
  EXPECT_EQ(a.input_min(), -20.0);
  EXPECT_EQ(a.input_max(), 120.0);
  EXPECT_EQ(a.config().input.max_v, 120.0);
  EXPECT_EQ(a.sample_period(), 1e-3);
}

TEST(SimulatedActuator, ConstructorRejectsBadConfigNamingTheField) {
  const auto message_of = [](const hs::SimulatedActuatorConfig& c, double dt) -> std::string {
    try {
      hs::SimulatedActuator a(c, dt);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no exception";
  };
  hs::SimulatedActuatorConfig c;
  EXPECT_NE(message_of(c, 0.0).find("dt_s"), std::string::npos);

  c = {};
  c.dynamics.natural_frequencies_hz[1] = 0.0;
  EXPECT_NE(message_of(c, 1e-4).find("dynamics.natural_frequencies_hz[1]"), std::string::npos);
  c.dynamics.enabled = false;
  EXPECT_EQ(message_of(c, 1e-4), "no exception");  // disabled effects are not checked

  const auto mpi = hs::SimulatedActuatorConfig::modified_pi_truth();
  c = mpi;
  c.creep.gains_um_per_v.pop_back();
  EXPECT_NE(message_of(c, 1e-4).find("creep.gains_um_per_v"), std::string::npos);

  c = mpi;
  c.hysteresis.play_thresholds_v[3] = c.hysteresis.play_thresholds_v[2];
  EXPECT_NE(message_of(c, 1e-4).find("hysteresis.play_thresholds_v[3]"), std::string::npos);

  c = mpi;
  c.hysteresis.dead_zone_thresholds_um = {-10.0, 5.0, 12.0};
  EXPECT_NE(message_of(c, 1e-4).find("hysteresis.dead_zone_thresholds_um"), std::string::npos);

  c = mpi;
  c.rate_dependence.enabled = true;
  c.rate_dependence.rate_coefficients.resize(3);
  EXPECT_NE(message_of(c, 1e-4).find("rate_dependence.rate_coefficients"), std::string::npos);

  c = {};
  c.hysteresis.coercive_spread = 0.0;
  EXPECT_NE(message_of(c, 1e-4).find("hysteresis.coercive_spread"), std::string::npos);

  c = {};
  c.creep.longest_s = 1.0;
  EXPECT_NE(message_of(c, 1e-4).find("creep.longest_s"), std::string::npos);

  c = {};
  c.sensor_filter.cutoff_hz = -5.0;
  EXPECT_NE(message_of(c, 1e-4).find("sensor_filter.cutoff_hz"), std::string::npos);

  c = {};
  c.rate_dependence.enabled = true;
  c.hysteresis.enabled = false;
  EXPECT_NE(message_of(c, 1e-4).find("rate_dependence.enabled"), std::string::npos);

  c = {};
  c.adc.bits = 0;
  EXPECT_NE(message_of(c, 1e-4).find("adc.bits"), std::string::npos);

  c = {};
  c.input.max_v = c.input.min_v;
  EXPECT_NE(message_of(c, 1e-4).find("input.max_v"), std::string::npos);

  c = {};
  c.sensor_noise.rms_um = -1.0;
  EXPECT_NE(message_of(c, 1e-4).find("sensor_noise.rms_um"), std::string::npos);
}
