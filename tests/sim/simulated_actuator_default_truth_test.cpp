// The simulated actuator's default truth: a 150 V stack's range and hysteresis, an asymmetric
// loop that saturates at its top, outside every PI family (no family's model, none fits it
// exactly), held by the Preisach plane, and named as the loop's shape by the diagnosis.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "hystbench/compensation/diagnosis.hpp"
#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/preisach_identification.hpp"
#include "hystbench/compensation/preisach_model.hpp"
#include "hystbench/sim/identification_excitation.hpp"
#include "hystbench/sim/major_loop_metrics.hpp"
#include "hystbench/sim/signal_generator.hpp"
#include "hystbench/sim/simulated_actuator.hpp"
#include "support/simulated_actuator_runs.hpp"

namespace hs = hystbench::sim;
using hystbench::testing::every_effect_off;
using hystbench::testing::ramp;
using hystbench::testing::run;

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
  // Modes well above the tracking band, lightly damped; a sensor of its own bandwidth; creep.
  EXPECT_TRUE(config.dynamics.enabled);
  ASSERT_EQ(config.dynamics.natural_frequencies_hz.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_GE(config.dynamics.natural_frequencies_hz[i], 2000.0);
    EXPECT_LE(config.dynamics.natural_frequencies_hz[i], 10000.0);
    EXPECT_LE(config.dynamics.damping_ratios[i], 0.1);
  }
  EXPECT_TRUE(config.sensor_filter.enabled);
  EXPECT_TRUE(config.creep.enabled);
  EXPECT_EQ(config.creep.law, hs::CreepLaw::kLogarithmic);
  EXPECT_EQ(config.hysteresis.kind, hs::HysteresisKind::kPreisach);
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

TEST(SimulatedActuatorDefault, TheLoopIsAsymmetricAndItsTopSaturates) {
  auto c = every_effect_off();
  c.hysteresis.enabled = true;
  EXPECT_GT(loop_asymmetry(c), 0.01);
  // The ascending branch flattens over the top tenth of the range: few relays are left there.
  hs::SimulatedActuator a(c, 1e-3);
  run(a, ramp(0.0, 150.0, 1501));
  run(a, ramp(150.0, 0.0, 1501));
  const auto up = run(a, ramp(0.0, 150.0, 1501)).truth;
  const double slope_mid = (up[825] - up[675]) / 15.0;
  const double slope_top = (up[1500] - up[1350]) / 15.0;
  EXPECT_LT(slope_top, 0.85 * slope_mid) << "mid " << slope_mid << " top " << slope_top;

  // The modified PI's loop is asymmetric through its dead zones, and symmetric without them.
  auto m = every_effect_off();
  m.hysteresis = hs::SimulatedActuatorConfig::modified_pi_truth().hysteresis;
  EXPECT_GT(loop_asymmetry(m), 0.01);
  m.hysteresis.dead_zone_thresholds_um = {0.0};
  m.hysteresis.dead_zone_weights = {1.0};
  EXPECT_LT(loop_asymmetry(m), 1e-9);
}

TEST(SimulatedActuatorDefault, NoModelFamilyIsTheTruth) {
  const hs::SimulatedActuatorConfig c;
  EXPECT_THROW(hs::make_truth_model(c, 1e-4), std::invalid_argument);
  for (const auto& [what, change] :
       std::vector<std::pair<std::string, void (*)(hs::SimulatedActuatorConfig&)>>{
           {"creep.law",
            [](hs::SimulatedActuatorConfig& x) { x.creep.law = hs::CreepLaw::kLogarithmic; }},
           {"sensor_filter",
            [](hs::SimulatedActuatorConfig& x) { x.sensor_filter.enabled = true; }},
           {"mode", [](hs::SimulatedActuatorConfig& x) {
              x.dynamics.natural_frequencies_hz = {3000.0, 8000.0};
              x.dynamics.damping_ratios = {0.05, 0.03};
              x.dynamics.mode_gains = {0.9, 0.1};
            }}}) {
    auto m = hs::SimulatedActuatorConfig::modified_pi_truth();
    change(m);
    EXPECT_THROW(hs::make_truth_model(m, 1e-4), std::invalid_argument) << what;
  }
  EXPECT_NO_THROW(hs::make_truth_model(hs::SimulatedActuatorConfig::modified_pi_truth(), 1e-4));
}

/// Held-out rms error [µm] of the bench's model family `kind` fitted to a noise-free record of
/// the static hysteresis of `c` (every other effect off) at 1 kHz.
double heldout_rms_of_fit(hs::SimulatedActuatorConfig c, hystbench::compensation::ModelKind kind) {
  const auto h = c.hysteresis;
  c = every_effect_off();
  c.hysteresis = h;
  const double dt = 1e-3;
  hs::SimulatedActuator a(c, dt);
  const auto x = hs::identification_excitation(0.0, 150.0, dt, {});
  a.reset(x.samples.front());
  std::vector<double> t, y;
  for (std::size_t k = 0; k < x.samples.size(); ++k) {
    t.push_back(static_cast<double>(k) * dt);
    y.push_back(a.step(x.samples[k]));
  }
  hystbench::compensation::FitOptions o;
  o.kind = kind;
  o.delay_samples = 0;
  return hystbench::compensation::fit_model(t, x.samples, y, o).heldout.rmse;
}

TEST(SimulatedActuatorDefault, NoModelFamilyFitsItsHysteresisExactly) {
  namespace hc = hystbench::compensation;
  // The modified-PI truth is recovered to within the fit's numerics; the Preisach truth is not,
  // by any family: what a fit leaves is the model's error, not noise.
  const auto mpi = hs::SimulatedActuatorConfig::modified_pi_truth();
  const double own = heldout_rms_of_fit(mpi, hc::ModelKind::kModifiedPi);
  EXPECT_LT(own, 0.01);
  for (const auto kind :
       {hc::ModelKind::kPi, hc::ModelKind::kModifiedPi, hc::ModelKind::kCoupledPlayPi}) {
    const double other = heldout_rms_of_fit(hs::SimulatedActuatorConfig{}, kind);
    RecordProperty(std::string(hc::to_string(kind)) + "_heldout_um", std::to_string(other));
    EXPECT_GT(other, 0.03) << hc::to_string(kind);
    EXPECT_GT(other, 5.0 * own) << hc::to_string(kind);
  }
}

/// The rms error [µm] of the plane `p` on a 1 Hz triangle between 20 and 130 V after the record
/// `u` it was fitted to, its model stepped over the record first and the truth `a` continuing
/// from the record's end; the first of four periods is not scored. The triangle's rising branches
/// start from a minimum inside the plane, where the record has few.
double triangle_after(const hystbench::compensation::PreisachParameters& p,
                      std::span<const double> u, hs::SimulatedActuator& a, double dt) {
  hystbench::compensation::PreisachModel model(p);
  model.reset(u.front());
  for (const double v : u) model.step(v);
  hs::SignalSpec spec;
  spec.kind = hs::SignalKind::kTriangle;
  spec.amplitude = 55.0;
  spec.offset = 75.0;
  spec.phase_rad = -0.5 * std::numbers::pi;  // from its minimum, rising
  const std::vector<double> triangle = hs::sample_signal(*hs::make_signal_generator(spec), dt, 4.0);
  const std::size_t period = triangle.size() / 4;
  double sum = 0.0;
  for (std::size_t k = 0; k < triangle.size(); ++k) {
    const double e = model.step(triangle[k]) - a.step(triangle[k]);
    if (k >= period) sum += e * e;
  }
  return std::sqrt(sum / static_cast<double>(triangle.size() - period));
}

// The Preisach family (a density on a 24 x 24 grid, no parametric form) on the same record:
// the default truth's loop, which every PI family misses (NoModelFamilyFitsItsHysteresisExactly),
// is held to less than half the coupled-play PI's error on the record's held-out quarter.
TEST(SimulatedActuatorDefault, ThePreisachFamilyHoldsItsLoop) {
  namespace hc = hystbench::compensation;
  hs::SimulatedActuatorConfig c = every_effect_off();
  c.hysteresis = hs::SimulatedActuatorConfig{}.hysteresis;
  const double dt = 1e-3;
  hs::SimulatedActuator a(c, dt);
  const auto x = hs::identification_excitation(0.0, 150.0, dt, {});
  a.reset(x.samples.front());
  std::vector<double> y;
  for (const double u : x.samples) y.push_back(a.step(u));
  const hc::PreisachFit fit = hc::fit_preisach(x.samples, y);
  RecordProperty("preisach_heldout_um", std::to_string(fit.heldout_rms));
  RecordProperty("preisach_smoothness", std::to_string(fit.smoothness));
  std::cout << "preisach 24 x 24: held-out " << fit.heldout_rms << " um, smoothness "
            << fit.smoothness << "\n";
  const double cpi =
      heldout_rms_of_fit(hs::SimulatedActuatorConfig{}, hc::ModelKind::kCoupledPlayPi);
  EXPECT_LT(fit.heldout_rms, 0.5 * cpi);
  // A truth that is a Preisach model: the plane predicts the triangle's branches too.
  const double triangle = triangle_after(fit.parameters, x.samples, a, dt);
  RecordProperty("preisach_triangle_um", std::to_string(triangle));
  EXPECT_LT(triangle, 0.5 * cpi);
  // Through fit_model (`fit --model preisach`): the same plane, its held-out error alike.
  const double by_name =
      heldout_rms_of_fit(hs::SimulatedActuatorConfig{}, hc::ModelKind::kPreisach);
  RecordProperty("fit_model_preisach_heldout_um", std::to_string(by_name));
  EXPECT_LT(by_name, 0.5 * cpi);
  // On the modified-PI truth (plays, then dead zones on the output: not a Preisach model, and a
  // record that starts where the plays, not the plane's relays, are relaxed): held below the
  // loopback sensor's 5 nm noise once the start-up is skipped, as fit_preisach does by default.
  c.hysteresis = hs::SimulatedActuatorConfig::modified_pi_truth().hysteresis;
  hs::SimulatedActuator b(c, dt);
  b.reset(x.samples.front());
  y.clear();
  for (const double u : x.samples) y.push_back(b.step(u));
  const hc::PreisachFit other = hc::fit_preisach(x.samples, y);
  std::cout << "preisach 24 x 24 on the modified-PI truth: held-out " << other.heldout_rms
            << " um\n";
  RecordProperty("preisach_on_mpi_truth_heldout_um", std::to_string(other.heldout_rms));
  EXPECT_GT(other.begin, 0u);
  EXPECT_LT(other.heldout_rms, 0.005);
  // Fitted from the record's first sample, the start-up's mismatch is in the fit.
  hc::PreisachFitOptions from_start;
  from_start.begin = 0;
  const hc::PreisachFit started = hc::fit_preisach(x.samples, y, from_start);
  RecordProperty("preisach_on_mpi_truth_from_start_heldout_um",
                 std::to_string(started.heldout_rms));
  EXPECT_GT(started.heldout_rms, 10.0 * other.heldout_rms);
  // The triangle after the record: its rising branches from a minimum inside the range are not
  // congruent on this truth (the output map bends each by where it lies), which relays alone do
  // not hold; measured, not asserted (docs/design/measurements-identify.md).
  RecordProperty("preisach_on_mpi_truth_triangle_um",
                 std::to_string(triangle_after(other.parameters, x.samples, b, dt)));
}

/// A noise-free record of the static hysteresis of `c` (every other effect off) at 1 kHz.
struct HysteresisRecord {
  std::vector<double> t, u, y;
};
HysteresisRecord hysteresis_record(const hs::SimulatedActuatorConfig::Hysteresis& h) {
  hs::SimulatedActuatorConfig c = every_effect_off();
  c.hysteresis = h;
  const double dt = 1e-3;
  hs::SimulatedActuator a(c, dt);
  HysteresisRecord r;
  r.u = hs::identification_excitation(0.0, 150.0, dt, {}).samples;
  a.reset(r.u.front());
  for (std::size_t k = 0; k < r.u.size(); ++k) {
    r.t.push_back(static_cast<double>(k) * dt);
    r.y.push_back(a.step(r.u[k]));
  }
  return r;
}

/// `diagnose --model` of a modified PI fitted to the record (as `fit --model mpi` writes it).
hystbench::compensation::Diagnosis diagnose_an_mpi_of(const HysteresisRecord& r) {
  namespace hc = hystbench::compensation;
  hc::FitOptions fit;
  fit.kind = hc::ModelKind::kModifiedPi;
  fit.delay_samples = 0;
  hc::DiagnosisOptions o;
  o.baseline = hc::fit_model(r.t, r.u, r.y, fit).model;
  return hc::diagnose(r.t, r.u, r.y, o);
}

// The diagnosis names the loop's shape where the plays miss it, and swaps the operator: on the
// default truth a modified PI leaves the shape, which a Preisach plane holds; on the modified-PI
// truth the same model is the truth, and the plane is not named.
TEST(SimulatedActuatorDefault, TheDiagnosisNamesTheLoopShapeTheModifiedPiMisses) {
  namespace hc = hystbench::compensation;
  const hc::Diagnosis d =
      diagnose_an_mpi_of(hysteresis_record(hs::SimulatedActuatorConfig{}.hysteresis));
  std::cout << "default truth: " << d.verdict << "\n";
  ASSERT_EQ(d.cause, hc::Cause::kLoopShape) << d.verdict;
  EXPECT_EQ(d.extended.hysteresis().kind(), hc::ModelKind::kPreisach);
  const double gain = d.baseline_heldout.rmse / d.extended_heldout.rmse;
  RecordProperty("default_truth_loop_shape_gain", std::to_string(gain));
  EXPECT_GT(gain, 2.0);

  const hc::Diagnosis m = diagnose_an_mpi_of(
      hysteresis_record(hs::SimulatedActuatorConfig::modified_pi_truth().hysteresis));
  std::cout << "modified-PI truth: " << m.verdict << "\n";
  for (const hc::NamedCause& n : m.causes) EXPECT_NE(n.cause, hc::Cause::kLoopShape) << m.verdict;
  EXPECT_EQ(m.extended.hysteresis().kind(), hc::ModelKind::kModifiedPi);
}
