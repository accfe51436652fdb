#include "hystbench/sim/simulated_actuator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include "hystbench/sim/major_loop_metrics.hpp"

namespace hs = hystbench::sim;

namespace {

/// A perfect linear actuator: every effect off (the hysteresis becomes its linear equivalent).
hs::SimulatedActuatorConfig bare() {
  hs::SimulatedActuatorConfig c;
  c.hysteresis.enabled = false;
  c.rate_dependence.enabled = false;
  c.creep.enabled = false;
  c.dynamics.enabled = false;
  c.delay.enabled = false;
  c.sensor_noise.enabled = false;
  c.dac.enabled = false;
  c.adc.enabled = false;
  c.thermal_drift.enabled = false;
  c.input_saturation.enabled = false;
  c.displacement_saturation.enabled = false;
  return c;
}

struct Run {
  std::vector<double> measured;
  std::vector<double> truth;
};

Run run(hs::SimulatedActuator& actuator, const std::vector<double>& u) {
  Run r;
  for (const double v : u) {
    r.measured.push_back(actuator.step(v));
    r.truth.push_back(actuator.true_position());
  }
  return r;
}

Run run_held(hs::SimulatedActuator& actuator, double u, std::size_t n) {
  return run(actuator, std::vector<double>(n, u));
}

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

std::vector<double> ramp(double from, double to, std::size_t n) {
  std::vector<double> u(n);
  for (std::size_t k = 0; k < n; ++k) u[k] = from + (to - from) * k / (n - 1.0);
  return u;
}

}  // namespace

TEST(SimulatedActuatorDefault, Resembles150VStackWith45umRangeAnd15To20PercentHysteresis) {
  const hs::SimulatedActuatorConfig config;
  EXPECT_EQ(config.input.min_v, 0.0);
  EXPECT_EQ(config.input.max_v, 150.0);
  const auto m = hs::measure_major_loop(config, 1e-4, 1.0, 3);
  RecordProperty("range_um", std::to_string(m.range_um));
  RecordProperty("hysteresis_percent", std::to_string(m.hysteresis_percent));
  EXPECT_GT(m.range_um, 40.0);
  EXPECT_LT(m.range_um, 50.0);
  EXPECT_GE(m.hysteresis_percent, 15.0);
  EXPECT_LE(m.hysteresis_percent, 20.0);
  // Resonance well above the tracking band, lightly damped.
  EXPECT_TRUE(config.dynamics.enabled);
  EXPECT_GE(config.dynamics.natural_frequency_hz, 2000.0);
  EXPECT_LE(config.dynamics.natural_frequency_hz, 5000.0);
  EXPECT_GE(config.dynamics.damping_ratio, 0.05);
  EXPECT_LE(config.dynamics.damping_ratio, 0.1);
  EXPECT_TRUE(config.creep.enabled);
}

/// Largest departure from point symmetry of the periodic major loop, over its range: a classical
/// PI loop is point-symmetric about its center, y_up(u) + y_down(u_min + u_max - u) = const.
double loop_asymmetry(const hs::SimulatedActuatorConfig& c) {
  hs::SimulatedActuator a(c, 1e-3);
  const auto up = ramp(0.0, 150.0, 1501), down = ramp(150.0, 0.0, 1501);
  run(a, up);
  run(a, down);
  const auto y_up = run(a, up).truth;
  const auto y_down = run(a, down).truth;  // y_down[k] is at u = 150 - up[k]
  const double reference = y_up.front() + y_down.front();
  double worst = 0.0;
  for (std::size_t k = 0; k < y_up.size(); ++k) {
    worst = std::max(worst, std::abs(y_up[k] + y_down[k] - reference));
  }
  return worst / (y_up.back() - y_up.front());
}

TEST(SimulatedActuatorDefault, DeadZonesMakeTheMajorLoopAsymmetric) {
  auto c = bare();
  c.hysteresis.enabled = true;
  EXPECT_GT(loop_asymmetry(c), 0.01);
  c.hysteresis.dead_zone_thresholds_um = {0.0};
  c.hysteresis.dead_zone_weights = {1.0};
  EXPECT_LT(loop_asymmetry(c), 1e-9);
}

TEST(SimulatedActuator, DeterministicPartEqualsTheTruthModel) {
  auto c = hs::SimulatedActuatorConfig{};
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
  auto with = bare();
  with.hysteresis.enabled = true;
  const auto h = hs::measure_major_loop(with, 1e-3);
  const auto l = hs::measure_major_loop(bare(), 1e-3);
  EXPECT_GT(h.hysteresis_percent, 10.0);
  EXPECT_NEAR(l.width_at_mid_um, 0.0, 1e-9);
  EXPECT_NEAR(l.range_um, h.range_um, 1e-3 * h.range_um);
  EXPECT_NEAR(l.min_um, h.min_um, 1e-3 * h.range_um);
}

TEST(SimulatedActuator, CreepKeepsTheOutputMovingDuringAHold) {
  const double dt = 1e-3;
  auto c = bare();
  c.creep.enabled = true;
  hs::SimulatedActuator creeping(c, dt);
  const auto y = run_held(creeping, 100.0, 20000).truth;
  for (std::size_t k = 1; k < y.size(); ++k) ASSERT_GE(y[k], y[k - 1]);
  EXPECT_GT(y[19999] - y[999], 0.05);  // still moving 1..20 s after the step [µm]

  hs::SimulatedActuator plain(bare(), dt);
  const auto z = run_held(plain, 100.0, 20000).truth;
  EXPECT_EQ(z.front(), z.back());
}

TEST(SimulatedActuator, DelayShiftsTheCrossCorrelationPeak) {
  const double dt = 1e-4;
  auto c = bare();
  c.delay.enabled = true;
  c.delay.delay_s = 2e-3;
  hs::SimulatedActuator delayed(c, dt);
  const auto u = random_input(4000, 0.0, 150.0);
  EXPECT_EQ(best_lag(u, run(delayed, u).measured, 60), 20);

  hs::SimulatedActuator plain(bare(), dt);
  EXPECT_EQ(best_lag(u, run(plain, u).measured, 60), 0);
}

TEST(SimulatedActuator, DynamicsRingAtTheDampedNaturalFrequencyAfterAStep) {
  const double dt = 1e-5;
  auto c = bare();
  c.dynamics.enabled = true;
  hs::SimulatedActuator ringing(c, dt);
  ringing.reset(0.0);
  const auto y = run_held(ringing, 75.0, 2000).truth;  // 20 ms
  const double final_um = y.back();
  // Count rising crossings of the final value over the first 3 ms.
  int crossings = 0;
  for (std::size_t k = 1; k < 300; ++k) crossings += (y[k - 1] < final_um && y[k] >= final_um);
  const double fn = c.dynamics.natural_frequency_hz, zeta = c.dynamics.damping_ratio;
  EXPECT_NEAR(crossings / 3e-3, fn * std::sqrt(1.0 - zeta * zeta), 1.0 / 3e-3);
  const double overshoot = (*std::max_element(y.begin(), y.end()) - final_um) /
                           (final_um - ringing.truth_model().peek_static(0.0));
  EXPECT_NEAR(overshoot, std::exp(-M_PI * zeta / std::sqrt(1.0 - zeta * zeta)), 0.02);

  hs::SimulatedActuator rigid(bare(), dt);
  rigid.reset(0.0);
  const auto z = run_held(rigid, 75.0, 2000).truth;
  EXPECT_EQ(*std::max_element(z.begin(), z.end()), z.front());
  EXPECT_EQ(z.front(), z.back());
}

TEST(SimulatedActuator, SensorNoiseHasTheConfiguredRmsAndIsSeeded) {
  auto c = bare();
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

  hs::SimulatedActuator quiet(bare(), 1e-4);
  const auto q = run_held(quiet, 75.0, 1000);
  EXPECT_EQ(q.measured, q.truth);
}

TEST(SimulatedActuator, AdcPutsTheMeasurementOnItsGrid) {
  auto c = bare();
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

  hs::SimulatedActuator fine(bare(), 1e-3);
  const auto f = run(fine, ramp(0.0, 150.0, 5000)).measured;
  EXPECT_EQ(std::set<double>(f.begin(), f.end()).size(), f.size());
}

TEST(SimulatedActuator, DacPutsTheAppliedVoltageOnItsGrid) {
  auto c = bare();
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

  hs::SimulatedActuator fine(bare(), 1e-3);
  fine.step(1.234567);
  EXPECT_EQ(fine.applied_input(), 1.234567);
}

TEST(SimulatedActuator, InputSaturationClampsToTheAmplifierRange) {
  auto c = bare();
  c.input_saturation.enabled = true;
  hs::SimulatedActuator clamped(c, 1e-3);
  hs::SimulatedActuator reference(c, 1e-3);
  clamped.step(200.0);
  reference.step(150.0);
  EXPECT_EQ(clamped.applied_input(), 150.0);
  EXPECT_EQ(clamped.true_position(), reference.true_position());
  clamped.step(-30.0);
  EXPECT_EQ(clamped.applied_input(), 0.0);

  hs::SimulatedActuator open(bare(), 1e-3);
  open.step(200.0);
  EXPECT_EQ(open.applied_input(), 200.0);
  EXPECT_GT(open.true_position(), reference.true_position());
}

TEST(SimulatedActuator, DisplacementSaturationClampsTheTruePosition) {
  auto c = bare();
  c.displacement_saturation = {true, 5.0, 30.0};
  hs::SimulatedActuator stopped(c, 1e-3);
  const auto r = run(stopped, ramp(0.0, 150.0, 1000));
  EXPECT_EQ(*std::max_element(r.truth.begin(), r.truth.end()), 30.0);
  EXPECT_EQ(*std::min_element(r.truth.begin(), r.truth.end()), 5.0);
  EXPECT_EQ(r.measured, r.truth);

  hs::SimulatedActuator free(bare(), 1e-3);
  const auto f = run(free, ramp(0.0, 150.0, 1000)).truth;
  EXPECT_GT(*std::max_element(f.begin(), f.end()), 40.0);
}

TEST(SimulatedActuator, SinusoidalDriftMovesTheHeldOutputSlowly) {
  const double dt = 1e-2;
  auto c = bare();
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

  hs::SimulatedActuator steady(bare(), dt);
  const auto z = run_held(steady, 75.0, 1000).truth;
  EXPECT_EQ(z.front(), z.back());
}

TEST(SimulatedActuator, RandomWalkDriftWandersWithinItsLimit) {
  const double dt = 1e-2;
  auto c = bare();
  c.thermal_drift.enabled = true;
  c.thermal_drift.shape = hs::DriftShape::kRandomWalk;
  c.thermal_drift.random_walk_um_per_sqrt_s = 0.05;
  c.thermal_drift.random_walk_limit_um = 0.3;
  hs::SimulatedActuator drifting(c, dt);
  hs::SimulatedActuator steady(bare(), dt);
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

TEST(SimulatedActuator, RateDependenceWidensTheLoopAtHigherRates) {
  auto c = bare();
  c.hysteresis.enabled = true;
  c.rate_dependence.enabled = true;
  const auto slow = hs::measure_major_loop(c, 1e-4, 1.0);
  const auto fast = hs::measure_major_loop(c, 1e-4, 10.0);
  EXPECT_GT(fast.width_at_mid_um, 1.2 * slow.width_at_mid_um);

  c.rate_dependence.enabled = false;
  const auto slow_ri = hs::measure_major_loop(c, 1e-4, 1.0);
  const auto fast_ri = hs::measure_major_loop(c, 1e-4, 10.0);
  EXPECT_NEAR(fast_ri.width_at_mid_um, slow_ri.width_at_mid_um, 0.01 * slow_ri.width_at_mid_um);
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
  auto c = bare();
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
  hs::SimulatedActuator a(bare(), 1e-3);
  a.step(42.0);
  const double before = a.true_position();
  a.step(std::nan(""));
  EXPECT_EQ(a.applied_input(), 42.0);
  EXPECT_EQ(a.true_position(), before);
  a.step(INFINITY);
  EXPECT_EQ(a.applied_input(), 42.0);
}

TEST(SimulatedActuator, ReportsItsInputRangeAndConfig) {
  auto c = bare();
  c.input = {-20.0, 120.0};
  hs::SimulatedActuator a(c, 1e-3);
  EXPECT_EQ(a.input_min(), -20.0);
  EXPECT_EQ(a.input_max(), 120.0);
  EXPECT_EQ(a.config().input.max_v, 120.0);
  EXPECT_EQ(a.sample_period(), 1e-3);
  EXPECT_EQ(a.truth_model().input_min, -20.0);
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
  c.dynamics.natural_frequency_hz = 0.0;
  EXPECT_NE(message_of(c, 1e-4).find("dynamics.natural_frequency_hz"), std::string::npos);
  c.dynamics.enabled = false;
  EXPECT_EQ(message_of(c, 1e-4), "no exception");  // disabled effects are not checked

  c = {};
  c.creep.gains_um_per_v.pop_back();
  EXPECT_NE(message_of(c, 1e-4).find("creep.gains_um_per_v"), std::string::npos);

  c = {};
  c.hysteresis.play_thresholds_v[3] = c.hysteresis.play_thresholds_v[2];
  EXPECT_NE(message_of(c, 1e-4).find("hysteresis.play_thresholds_v[3]"), std::string::npos);

  c = {};
  c.hysteresis.dead_zone_thresholds_um = {-10.0, 5.0, 12.0};
  EXPECT_NE(message_of(c, 1e-4).find("hysteresis.dead_zone_thresholds_um"), std::string::npos);

  c = {};
  c.rate_dependence.enabled = true;
  c.rate_dependence.rate_coefficients.resize(3);
  EXPECT_NE(message_of(c, 1e-4).find("rate_dependence.rate_coefficients"), std::string::npos);

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
