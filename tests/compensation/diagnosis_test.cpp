// Diagnosis: the hidden-effect suite. Each case builds a simulated actuator
// (sim::SimulatedActuator) whose truth is a point-symmetric Preisach hysteresis (no model family
// contains it, so nothing is found only because the base is a PI) plus exactly one hidden effect
// (or none; two in the several-causes tests),
// with randomised parameters, seeds, sample rates and noise; drives it with the identification
// excitation; and checks that diagnose() names the effect from the data alone (it sees t, u, y and
// nothing of the configuration) and that the extended model's error on a second, independent record
// of the same actuator (scored as validate_model scores a record never fitted) is at most 0.8x the
// baseline's (0.9x for creep, 1x for a drift: see max_ratio). A classical PI baseline misses the
// Preisach base's bent loop: with nothing hidden the diagnosis names that shape (asymmetry, "bent
// or asymmetric") or nothing; a hidden effect is named on top of the shape. The shape's error stays
// in part in both models on the second record, which bounds the ratio. The sweep (64 cases: 8 per
// cause and none at 100 Hz .. 20 kHz, all asserted; plus 8 random-walk drifts, reported in their
// own row; confusion table and per-cause ratios printed) runs with HYSTBENCH_LONG_TESTS=1
// (HYSTBENCH_SWEEP_SEED draws other cases, HYSTBENCH_SWEEP_CAUSE=<cause> runs the cases that hide
// it, HYSTBENCH_SWEEP_VERBOSE=1 prints every case's report, not only a wrong one's); by default one
// case per cause runs, at several sample rates.
#include "hystbench/compensation/diagnosis.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/sim/identification_excitation.hpp"
#include "hystbench/sim/preisach_hysteresis.hpp"
#include "hystbench/sim/simulated_actuator.hpp"
#include "hystbench/sim/thermal_drift.hpp"

namespace hc = hystbench::compensation;
namespace hs = hystbench::sim;

namespace {

constexpr double kMaxRatio = 0.8;  // extended / baseline rms on the second record

// The bound on the second record's ratio for a named cause. A drift is fitted and removed, not
// carried into the extended model (a drift does not repeat), so on another record the extended
// model gains only what the drift-free refit gains, little where the drift was small: it must
// not be worse.
// A logarithmic creep has lags far longer than a record, whose part the first record shows
// predicts the second only in part: 0.9 (seeds 1000 / 2000: worst 0.61 / 0.80).
double max_ratio(hc::Cause named) {
  if (named == hc::Cause::kDrift) return 1.0;
  return named == hc::Cause::kCreep ? 0.9 : kMaxRatio;
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

struct Record {
  std::vector<double> t, u, y;
};

// The excitation of the first record, and a different one (other rates, order of reversals and
// hold levels, loop frequencies) for the second, independent record.
hs::IdentificationExcitationOptions excitation_options(double fs, bool second,
                                                       std::mt19937_64& rng) {
  hs::IdentificationExcitationOptions o;
  const double fastest = std::min(10.0, fs / 20.0);
  o.hold_s = 2.0;
  if (!second) {
    o.rate_frequencies_hz = {0.5, 2.0, fastest};
    return o;
  }
  o.major_loop_frequency_hz = 0.3;
  o.minor_loop_frequency_hz = 1.5;
  o.minor_loops = 6;
  o.rate_frequencies_hz = {1.0, 0.7 * fastest};
  o.rate_cycles = {3, 8};
  std::shuffle(o.reversal_points.begin(), o.reversal_points.end() - 1, rng);
  o.hold_levels = {uniform(rng, 0.6, 0.9), uniform(rng, 0.05, 0.3), 1.0, uniform(rng, 0.3, 0.6),
                   0.0};
  return o;
}

Record run(hs::SimulatedActuator& actuator, const hs::Excitation& x) {
  Record r;
  actuator.reset(x.samples.front());
  for (std::size_t k = 0; k < x.samples.size(); ++k) {
    r.t.push_back(static_cast<double>(k) * x.dt_s);
    r.u.push_back(x.samples[k]);
    r.y.push_back(actuator.step(x.samples[k]));
  }
  return r;
}

// Scales the relays of h (and its offset) so that its periodic 0..150 V major loop spans 0..40 um
// with its reversible slope as it is.
void scale_to_40um(hs::SimulatedActuatorConfig::Hysteresis& h) {
  hs::PreisachHysteresis relays(hs::PreisachParameters{0.0, 150.0, h.coercive_median_v,
                                                       h.coercive_spread, h.bias_mean_v,
                                                       h.bias_std_v, 1.0, h.grid_points});
  relays.step(150.0);
  const double bottom = relays.step(0.0);
  const double span = relays.step(150.0) - bottom;
  h.switching_um = (40.0 - h.reversible_um_per_v * 150.0) / span;
  h.offset_um = -bottom * h.switching_um;
}

// Point-symmetric Preisach truth (its relay centres spread evenly about mid-range): random relay
// widths and spreads and a random reversible share of a 40 um major loop from 0 um.
hs::SimulatedActuatorConfig::Hysteresis random_preisach(std::mt19937_64& rng) {
  hs::SimulatedActuatorConfig::Hysteresis h;
  h.kind = hs::HysteresisKind::kPreisach;
  h.coercive_median_v = uniform(rng, 8.0, 25.0);
  h.coercive_spread = uniform(rng, 0.35, 0.8);
  h.bias_mean_v = 75.0;
  h.bias_std_v = uniform(rng, 45.0, 90.0);
  h.grid_points = 257;
  h.reversible_um_per_v = uniform(rng, 0.3, 0.7) * 40.0 / 150.0;
  scale_to_40um(h);
  return h;
}

struct HiddenCase {
  hc::Cause cause = hc::Cause::kNone;
  double fs = 1000.0;
  std::uint64_t seed = 1;
  /// Drift only: a random walk instead of the slow (thermal) sinusoid. Its fast part is beyond
  /// any slow drift model and leaks into the hysteresis fit, so only the naming is checked.
  bool random_walk = false;
  /// Dynamics only: the resonance [Hz] and damping; 0 = drawn at random.
  double natural_frequency_hz = 0.0;
  double damping_ratio = 0.0;
  /// A second hidden effect (none: one effect only).
  hc::Cause also = hc::Cause::kNone;
  /// Rate dependence only: relays whose thresholds widen with |du/dt| instead of a switching
  /// front.
  bool widening_thresholds = false;
};

// Two effects at once, the rate effect (one of them) by widening thresholds.
HiddenCase with_widening_law(hc::Cause cause, double fs, std::uint64_t seed, hc::Cause also) {
  HiddenCase c{cause, fs, seed};
  c.also = also;
  c.widening_thresholds = true;
  return c;
}

std::string name_of(const HiddenCase& c) {
  auto label = [&](hc::Cause cause) {
    return std::string(hc::to_string(cause)) +
           (cause == hc::Cause::kRateDependence && c.widening_thresholds ? " (thresholds)" : "");
  };
  return label(c.cause) + (c.random_walk ? " (walk)" : "") +
         (c.also != hc::Cause::kNone ? " + " + label(c.also) : "") + " at " +
         std::to_string(static_cast<int>(c.fs)) + " Hz, seed " + std::to_string(c.seed);
}

struct HiddenData {
  hs::SimulatedActuatorConfig config;
  Record first, second;
  Record second_without_drift;  // the second record minus its (known) drift
  std::string truth;            // what was hidden, for messages
};

// Rate dependence hidden in c: relays whose thresholds widen with |du/dt|, or relays behind a
// switching front; returns what was hidden.
std::string hide_rate_dependence(const HiddenCase& hc_case, hs::SimulatedActuatorConfig& c,
                                 std::mt19937_64& rng) {
  const double dt = 1.0 / hc_case.fs;
  char buf[256];
  c.rate_dependence.enabled = true;
  if (hc_case.widening_thresholds) {
    // Relays whose thresholds widen with |du/dt|: the loop widens in proportion to the
    // rate, its tips stay at the reversals.
    c.rate_dependence.mechanism = hs::RateMechanism::kSwitchingThresholds;
    c.rate_dependence.threshold_rate_s = uniform(rng, 1e-3, 3e-3);  // as the delays
    c.rate_dependence.threshold_filter_s = std::round(uniform(rng, 0.0, 3.0)) * dt;
    std::snprintf(
        buf, sizeof buf, "; rate dependence: thresholds widening %.2f V per kV/s, filter %.2f ms",
        c.rate_dependence.threshold_rate_s * 1e3, c.rate_dependence.threshold_filter_s * 1e3);
    return buf;
  }
  // Relays behind a switching front: the loop widens with the square root of the rate.
  c.rate_dependence.mechanism = hs::RateMechanism::kSwitchingFront;
  c.rate_dependence.switching_lag_v = uniform(rng, 4.0, 8.0);
  std::snprintf(buf, sizeof buf, "; rate dependence: switching front %.1f V behind 1 kV/s",
                c.rate_dependence.switching_lag_v);
  return buf;
}

// A thermal drift hidden in c: a slow sinusoid, or a random walk; returns what was hidden.
std::string hide_drift(const HiddenCase& hc_case, hs::SimulatedActuatorConfig& c,
                       std::mt19937_64& rng) {
  char buf[256];
  c.thermal_drift.enabled = true;
  c.thermal_drift.seed = rng();
  if (!hc_case.random_walk) {
    c.thermal_drift.shape = hs::DriftShape::kSinusoid;
    c.thermal_drift.amplitude_um = uniform(rng, 0.3, 1.5);
    c.thermal_drift.period_s = uniform(rng, 40.0, 300.0);
    std::snprintf(buf, sizeof buf, "; drift sinusoid %.2f um period %.0f s",
                  c.thermal_drift.amplitude_um, c.thermal_drift.period_s);
  } else {
    c.thermal_drift.shape = hs::DriftShape::kRandomWalk;
    c.thermal_drift.random_walk_um_per_sqrt_s = uniform(rng, 0.01, 0.05);
    c.thermal_drift.random_walk_limit_um = 1.0;
    std::snprintf(buf, sizeof buf, "; drift random walk %.3f um/sqrt(s)",
                  c.thermal_drift.random_walk_um_per_sqrt_s);
  }
  return buf;
}

// Hides `cause` in c (drawing its parameters from rng); returns what was hidden, for messages.
std::string hide(hc::Cause cause, const HiddenCase& hc_case, hs::SimulatedActuatorConfig& c,
                 std::mt19937_64& rng) {
  const double fs = hc_case.fs;
  const double dt = 1.0 / fs;
  char buf[256];
  switch (cause) {
    case hc::Cause::kNone:
    case hc::Cause::kLoopShape:  // the baseline truth is a Preisach plane already
      return "";
    case hc::Cause::kAsymmetry: {
      // The relay centres sit off mid-range: the loop loses its point symmetry.
      const double shift = uniform(rng, 15.0, 35.0) * (rng() % 2 ? 1.0 : -1.0);
      c.hysteresis.bias_mean_v = 75.0 + shift;
      scale_to_40um(c.hysteresis);
      std::snprintf(buf, sizeof buf, "; relay centres %+.0f V off mid-range", shift);
      break;
    }
    case hc::Cause::kRateDependence:
      return hide_rate_dependence(hc_case, c, rng);
    case hc::Cause::kCreep: {
      c.creep.enabled = true;
      c.creep.law = hs::CreepLaw::kLogarithmic;
      c.creep.fraction_per_decade = uniform(rng, 0.015, 0.04);
      c.creep.longest_s = uniform(rng, 1e3, 1e5);
      std::snprintf(buf, sizeof buf, "; logarithmic creep %.1f %% per decade",
                    100 * c.creep.fraction_per_decade);
      break;
    }
    case hc::Cause::kDynamics: {
      c.dynamics.enabled = true;
      const double fastest = std::min(10.0, fs / 20.0);
      double fn = uniform(rng, 3.0 * fastest, std::min(0.25 * fs, 20.0 * fastest));
      double zeta = uniform(rng, 0.02, 0.15);
      if (hc_case.natural_frequency_hz > 0.0) {
        fn = hc_case.natural_frequency_hz;
        zeta = hc_case.damping_ratio;
      }
      c.dynamics.natural_frequencies_hz = {fn};
      c.dynamics.damping_ratios = {zeta};
      c.dynamics.mode_gains = {1.0};
      std::snprintf(buf, sizeof buf, "; dynamics %.1f Hz zeta %.3f", fn, zeta);
      break;
    }
    case hc::Cause::kDelay: {
      c.delay.enabled = true;
      const double lo = std::max(1.0, 0.0005 * fs), hi = std::max(1.0, 0.003 * fs);
      const double samples = std::round(uniform(rng, lo, hi));
      c.delay.delay_s = samples * dt;
      std::snprintf(buf, sizeof buf, "; delay %.0f samples", samples);
      break;
    }
    case hc::Cause::kDrift:
      return hide_drift(hc_case, c, rng);
  }
  return buf;
}

HiddenData make_hidden(const HiddenCase& hc_case) {
  std::mt19937_64 rng(hc_case.seed);
  const double fs = hc_case.fs;
  const double dt = 1.0 / fs;
  HiddenData d;
  hs::SimulatedActuatorConfig& c = d.config;
  c.creep.enabled = false;
  c.dynamics.enabled = false;
  c.sensor_filter.enabled = false;
  c.delay.enabled = false;
  c.rate_dependence.enabled = false;
  c.thermal_drift.enabled = false;
  c.displacement_saturation.enabled = false;
  c.hysteresis = random_preisach(rng);
  c.sensor_noise.enabled = true;
  c.sensor_noise.rms_um = uniform(rng, 0.003, 0.02);
  c.sensor_noise.seed = rng();
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "Preisach h_c %.1f V (spread %.2f), h_b 75 +- %.0f V, reversible %.3f um/V, "
                "noise %.3f um",
                c.hysteresis.coercive_median_v, c.hysteresis.coercive_spread,
                c.hysteresis.bias_std_v, c.hysteresis.reversible_um_per_v, c.sensor_noise.rms_um);
  d.truth = buf;
  const auto x1 = hs::identification_excitation(0.0, 150.0, dt, excitation_options(fs, false, rng));
  const auto x2 = hs::identification_excitation(0.0, 150.0, dt, excitation_options(fs, true, rng));
  d.truth += hide(hc_case.cause, hc_case, c, rng);
  d.truth += hide(hc_case.also, hc_case, c, rng);
  hs::SimulatedActuator first(c, dt);
  d.first = run(first, x1);
  // The same actuator, another day: new noise (and a new drift) on another excitation.
  hs::SimulatedActuatorConfig c2 = c;
  c2.sensor_noise.seed = rng();
  c2.thermal_drift.seed = rng();
  if (c2.thermal_drift.shape == hs::DriftShape::kSinusoid) {
    c2.thermal_drift.amplitude_um *= uniform(rng, 0.5, 1.0);
    c2.thermal_drift.period_s *= uniform(rng, 0.7, 1.3);
  }
  hs::SimulatedActuator second(c2, dt);
  d.second = run(second, x2);
  d.second_without_drift = d.second;
  if (c2.thermal_drift.enabled) {
    hs::ThermalDrift drift(c2.thermal_drift, dt);
    drift.reset();
    for (double& y : d.second_without_drift.y) y -= drift.step();
  }
  return d;
}

// rms of measured - model over a whole record.
double rms_error(hc::ActuatorModel model, const Record& r) {
  const double dt = r.t[1] - r.t[0];
  const std::vector<double> yhat = model.simulate(r.u, dt);
  return hc::error_stats(r.y, yhat).rmse;
}

struct Outcome {
  hc::Cause named = hc::Cause::kNone;
  double ratio = 0.0;      // extended / baseline rms on the second record (validate_model)
  double raw_ratio = 0.0;  // the same over the whole second record, from its first sample
  double gain = 0.0;       // held-out gain of the named cause
  double seconds = 0.0;
  std::size_t samples = 0;
  hc::Diagnosis diagnosis;
};

Outcome diagnose_case(const HiddenData& d) {
  Outcome o;
  const auto start = std::chrono::steady_clock::now();
  o.diagnosis = hc::diagnose(d.first.t, d.first.u, d.first.y);
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  o.samples = d.first.u.size();
  o.named = o.diagnosis.cause;
  o.gain = o.diagnosis.baseline_heldout.rmse / o.diagnosis.extended_heldout.rmse;
  // Drift is a disturbance of the day, not part of any model: both models are judged on the
  // second record without its drift (the test knows it; the diagnosis never does). They are
  // scored as the product scores a record never fitted (validate_model: after the start-up, whose
  // virgin state no fit that leaves out its own start-up has seen, the mean error apart);
  // raw_ratio scores the whole record from its first sample.
  const Record& r2 = d.second_without_drift;
  const double dt2 = r2.t[1] - r2.t[0];
  o.ratio = hc::validate_model(o.diagnosis.extended, r2.u, r2.y, dt2).rmse /
            hc::validate_model(o.diagnosis.baseline, r2.u, r2.y, dt2).rmse;
  o.raw_ratio = rms_error(o.diagnosis.extended, r2) / rms_error(o.diagnosis.baseline, r2);
  return o;
}

std::string summary(const Outcome& o) {
  std::string s = "named " + std::string(hc::to_string(o.named)) + "; " + o.diagnosis.verdict +
                  "\n  baseline held-out " + std::to_string(o.diagnosis.baseline_heldout.rmse) +
                  ", noise " + std::to_string(o.diagnosis.noise_rms) + "\n";
  for (const auto& c : o.diagnosis.candidates) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "  %-16s stat %8.3g (thr %5.3g) gain %7.3f fit %.4f held %.4f ",
                  std::string(hc::to_string(c.cause)).c_str(), c.statistic, c.threshold, c.gain,
                  c.fit.rmse, c.heldout.rmse);
    s += buf + c.extension + (c.named ? "" : "\n    not named: " + c.not_named) + "\n";
  }
  for (const auto& n : o.diagnosis.causes) {
    s += "  named " + std::string(hc::to_string(n.cause)) + " gain " + std::to_string(n.gain) +
         " over " + n.against + ", adds " + std::to_string(n.added_rms) + "\n";
  }
  for (const auto& n : o.diagnosis.notes) s += "  note: " + n + "\n";
  return s;
}

void expect_named(const HiddenCase& c) {
  const HiddenData d = make_hidden(c);
  const Outcome o = diagnose_case(d);
  SCOPED_TRACE(name_of(c) + " (" + d.truth + ")\n" + summary(o));
  if (c.cause != hc::Cause::kNone) {
    EXPECT_EQ(o.named, c.cause);
    EXPECT_LE(o.ratio, max_ratio(c.cause)) << "extended / baseline rms on the second record";
    EXPECT_GE(o.gain, 1.2);
  } else if (o.named == hc::Cause::kAsymmetry) {
    // Only the base's shape: what it gains carries over.
    EXPECT_LE(o.ratio, kMaxRatio) << "extended / baseline rms on the second record";
  } else {
    EXPECT_EQ(o.named, hc::Cause::kNone);
    EXPECT_EQ(o.ratio, 1.0);
  }
}

bool long_tests() {
  const char* v = std::getenv("HYSTBENCH_LONG_TESTS");
  return v != nullptr && std::string(v) == "1";
}

}  // namespace

// ------------------------------------------------------------------------ names and bad input

TEST(Diagnosis, CauseNamesRoundTrip) {
  EXPECT_EQ(hc::to_string(hc::Cause::kNone), "none");
  for (const hc::Cause c : hc::candidate_causes()) {
    EXPECT_EQ(hc::cause_from_string(hc::to_string(c)), c);
  }
  EXPECT_EQ(hc::candidate_causes().size(), 7u);
  EXPECT_EQ(hc::cause_from_string("rate_dependence"), hc::Cause::kRateDependence);
  EXPECT_EQ(hc::cause_from_string("loop_shape"), hc::Cause::kLoopShape);
  EXPECT_FALSE(hc::cause_from_string("resonance").has_value());
}

TEST(Diagnosis, RejectsBadRecordsWithAClearMessage) {
  auto message = [](const std::vector<double>& t, const std::vector<double>& u,
                    const std::vector<double>& y) -> std::string {
    try {
      hc::diagnose(t, u, y);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no error)";
  };
  std::vector<double> t(1000), u(1000), y(1000);
  for (std::size_t k = 0; k < t.size(); ++k) {
    t[k] = 1e-3 * static_cast<double>(k);
    u[k] = 50.0 + 40.0 * std::sin(0.02 * static_cast<double>(k));
    y[k] = 0.3 * u[k];
  }
  EXPECT_NE(message({t.begin(), t.begin() + 100}, {u.begin(), u.begin() + 100},
                    {y.begin(), y.begin() + 100})
                .find("too few samples"),
            std::string::npos);
  EXPECT_NE(message(t, std::vector<double>(1000, 3.0), y).find("input u is constant"),
            std::string::npos);
  auto bad = y;
  bad[17] = std::nan("");
  EXPECT_NE(message(t, u, bad).find("y[17] is not a finite number"), std::string::npos);
  EXPECT_NE(message(t, u, std::vector<double>(999, 1.0)).find("same length"), std::string::npos);
  EXPECT_NE(message(t, u, std::vector<double>(1000, 2.0)).find("output y is constant"),
            std::string::npos);
  auto back = t;
  back[500] = back[499];
  EXPECT_NE(message(back, u, y).find("strictly increasing"), std::string::npos);
}

// ------------------------------------------------------------------------ hidden effects

TEST(DiagnosisHiddenEffect, NamesNothingBeyondTheShapeOfAPreisachWithNoise) {
  expect_named({hc::Cause::kNone, 200.0, 101});
}
TEST(DiagnosisHiddenEffect, NamesAsymmetryForOffCentreRelays) {
  expect_named({hc::Cause::kAsymmetry, 1000.0, 102});
}
// Relays behind a switching front: the loop widens with the square root of the rate. At 500 Hz
// the linear laws gain too little to be named beside the loop's shape; thresholds widening with
// |du/dt|^(1/2) follow it.
TEST(DiagnosisHiddenEffect, NamesRateDependenceBehindASwitchingFront) {
  expect_named({hc::Cause::kRateDependence, 2000.0, 103});
  expect_named({hc::Cause::kRateDependence, 500.0, 2019});
}
TEST(DiagnosisHiddenEffect, NamesCreep) { expect_named({hc::Cause::kCreep, 500.0, 104}); }
TEST(DiagnosisHiddenEffect, NamesDynamics) { expect_named({hc::Cause::kDynamics, 5000.0, 105}); }
TEST(DiagnosisHiddenEffect, NamesDelay) { expect_named({hc::Cause::kDelay, 1000.0, 106}); }
TEST(DiagnosisHiddenEffect, NamesDrift) { expect_named({hc::Cause::kDrift, 1000.0, 107}); }

// A Preisach plane as the baseline (`diagnose --model` of what `fit --model preisach` wrote): the
// effect hidden beside the relays is named on top of it, the extension keeps the plane (its shape
// fixed, its scale refitted), and the extended model predicts the second record better. The rate
// law's baseline is a plane fitted without one; its extension is the plane's relays widening.
TEST(DiagnosisHiddenEffect, NamesTheEffectBesideAPreisachBaseline) {
  for (const HiddenCase& c :
       {HiddenCase{hc::Cause::kCreep, 500.0, 104}, HiddenCase{hc::Cause::kDynamics, 5000.0, 105},
        HiddenCase{hc::Cause::kRateDependence, 500.0, 2019}}) {
    const HiddenData d = make_hidden(c);
    hc::FitOptions fit;
    fit.kind = hc::ModelKind::kPreisach;
    fit.delay_samples = 0;
    fit.preisach_rate_law = false;
    hc::DiagnosisOptions o;
    const hc::FitResult plane = hc::fit_model(d.first.t, d.first.u, d.first.y, fit);
    ASSERT_EQ(plane.model.hysteresis().kind(), hc::ModelKind::kPreisach)
        << testing::PrintToString(plane.notes);
    o.baseline = plane.model;
    const hc::Diagnosis dg = hc::diagnose(d.first.t, d.first.u, d.first.y, o);
    SCOPED_TRACE(name_of(c) + ": " + d.truth);
    EXPECT_EQ(dg.cause, c.cause) << hc::to_string(dg.cause);
    EXPECT_EQ(dg.extended.hysteresis().kind(), hc::ModelKind::kPreisach)
        << testing::PrintToString(dg.extended_parts)
        << (dg.causes.empty() ? "" : dg.causes.front().extension);
    const Record& r2 = d.second_without_drift;
    const double dt2 = r2.t[1] - r2.t[0];
    const double ratio = hc::validate_model(dg.extended, r2.u, r2.y, dt2).rmse /
                         hc::validate_model(dg.baseline, r2.u, r2.y, dt2).rmse;
    std::printf("%s on a Preisach baseline: named %s, gain %.2f, second record %.3fx\n",
                name_of(c).c_str(), std::string(hc::to_string(dg.cause)).c_str(),
                dg.baseline_heldout.rmse / dg.extended_heldout.rmse, ratio);
    EXPECT_LT(ratio, 0.9);
    if (c.cause == hc::Cause::kRateDependence) {
      EXPECT_TRUE(dg.extended.hysteresis().thresholds_law());
    }
  }
}

// The resonance is fitted jointly with the weights (variable projection), not only named: its
// natural frequency within 2 % and its damping within 20 %, across the range the bench meets
// (50 Hz to a fifth of the sample rate, damping 0.02 to 0.2). The first case is the one a user
// met: 107 Hz, damping 0.078 at 1 kHz, read as 99.7 Hz and 0.131 by a fit of the baseline alone.
TEST(DiagnosisHiddenEffect, FitsTheResonanceItNames) {
  const HiddenCase cases[] = {{hc::Cause::kDynamics, 1000.0, 211, false, 107.0, 0.078},
                              {hc::Cause::kDynamics, 1000.0, 212, false, 55.0, 0.2},
                              {hc::Cause::kDynamics, 2000.0, 213, false, 380.0, 0.03},
                              {hc::Cause::kDynamics, 5000.0, 214, false, 160.0, 0.02}};
  for (const HiddenCase& c : cases) {
    const HiddenData d = make_hidden(c);
    const Outcome o = diagnose_case(d);
    SCOPED_TRACE(name_of(c) + " (" + d.truth + ")\n" + summary(o));
    ASSERT_EQ(o.named, hc::Cause::kDynamics);
    ASSERT_TRUE(o.diagnosis.extended.dynamics().has_value());
    const hc::DynamicsParameters& fitted = *o.diagnosis.extended.dynamics();
    std::printf("%.0f Hz zeta %.3f at %.0f Hz: fitted %.2f Hz zeta %.4f, ratio %.3f, gain %.2f\n",
                c.natural_frequency_hz, c.damping_ratio, c.fs, fitted.natural_frequency_hz,
                fitted.damping_ratio, o.ratio, o.gain);
    EXPECT_NEAR(fitted.natural_frequency_hz, c.natural_frequency_hz, 0.02 * c.natural_frequency_hz);
    EXPECT_NEAR(fitted.damping_ratio, c.damping_ratio, 0.2 * c.damping_ratio);
    // The base's shape error stays in part in both models (see the file's header).
    EXPECT_LE(o.ratio, 0.6) << "extended / baseline rms on the second record";
  }
}

// The extended model is an ordinary model file: it survives the JSON round trip and predicts
// the second record exactly as the in-memory model does.
TEST(DiagnosisHiddenEffect, ExtendedModelRoundTripsThroughAModelFile) {
  const HiddenCase c{hc::Cause::kCreep, 500.0, 104};
  const HiddenData d = make_hidden(c);
  const hc::Diagnosis dg = hc::diagnose(d.first.t, d.first.u, d.first.y);
  ASSERT_EQ(dg.cause, hc::Cause::kCreep);
  ASSERT_TRUE(dg.extended.creep().has_value());
  const hc::ModelFile back = hc::model_file_from_json(hc::to_json(hc::ModelFile{dg.extended, {}}));
  EXPECT_NEAR(rms_error(back.model, d.second), rms_error(dg.extended, d.second), 1e-9);
}

// ------------------------------------------------------------------------ several causes

namespace {

// A runner-up within this share of the first cause's gain is as good as tied with it.
constexpr double kAmbiguity = 0.9;

// Whether a delay gaining within 10 % of a rate law was named before it for its error after the
// input's reversals (the report's note says so).
bool ordered_after_reversals(const hc::Diagnosis& d) {
  return std::any_of(d.notes.begin(), d.notes.end(), [](const std::string& s) {
    return s.find("after the input's reversals") != std::string::npos &&
           s.find("the delay is named first") != std::string::npos;
  });
}

// What every list of named causes holds: `cause` first, gaining min_gain; each named cause
// carrying over and, after the first, gaining 1.1x added to the causes before it and explaining
// beyond them more than the noise allows; ranked by gain among those judged against the same
// model (a delay within 10 % of a rate law's gain may go first for its error after the
// reversals), the shape (judged on top of the first) last; every other candidate says why not.
void expect_ranked(const hc::Diagnosis& d) {
  ASSERT_FALSE(d.causes.empty());
  EXPECT_EQ(d.cause, d.causes.front().cause);
  EXPECT_NEAR(d.noise_allowance_rms, std::sqrt(1.3 * 1.3 - 1.0) * d.noise_rms, 1e-12);
  for (std::size_t i = 0; i < d.causes.size(); ++i) {
    const hc::NamedCause& n = d.causes[i];
    SCOPED_TRACE(std::string(hc::to_string(n.cause)));
    const hc::CandidateReport* c = d.candidate(n.cause);
    ASSERT_NE(c, nullptr);
    EXPECT_TRUE(c->named);
    EXPECT_TRUE(c->carries_over);
    if (i == 0) {
      EXPECT_GE(n.gain, 1.2);
      continue;
    }
    EXPECT_GE(n.added_gain, 1.1);
    EXPECT_GE(n.added_rms, d.noise_allowance_rms);
    const bool shape_last = n.cause == hc::Cause::kAsymmetry && i + 1 == d.causes.size();
    if (n.against == d.causes[i - 1].against && !shape_last) {
      const bool by_reversals = i == 1 && ordered_after_reversals(d);
      EXPECT_LE(n.gain, (by_reversals ? 1.0 / kAmbiguity : 1.0) * d.causes[i - 1].gain);
    }
  }
  for (const hc::CandidateReport& c : d.candidates) {
    const bool listed = std::any_of(d.causes.begin(), d.causes.end(),
                                    [&](const hc::NamedCause& n) { return n.cause == c.cause; });
    EXPECT_EQ(c.named, listed) << hc::to_string(c.cause);
    EXPECT_EQ(c.not_named.empty(), c.named) << hc::to_string(c.cause) << ": " << c.not_named;
  }
}

// A case diagnosed and its list of named causes checked; `trace` says what was hidden and what
// the diagnosis saw, for the caller's SCOPED_TRACE.
struct RankedCase {
  Outcome o;
  std::string trace;
};
RankedCase diagnose_ranked(const HiddenCase& c) {
  const HiddenData d = make_hidden(c);
  RankedCase r{diagnose_case(d), ""};
  r.trace = name_of(c) + " (" + d.truth + ")\n" + summary(r.o);
  SCOPED_TRACE(r.trace);
  expect_ranked(r.o.diagnosis);
  return r;
}

std::vector<hc::Cause> named_causes(const hc::Diagnosis& d) {
  std::vector<hc::Cause> v;
  for (const hc::NamedCause& n : d.causes) v.push_back(n.cause);
  return v;
}

bool names(const std::vector<hc::Cause>& named, hc::Cause cause) {
  return std::find(named.begin(), named.end(), cause) != named.end();
}

/// `first` named first, and `also` named after it.
void expect_named_first_and(const std::vector<hc::Cause>& named, hc::Cause first, hc::Cause also) {
  ASSERT_FALSE(named.empty());
  EXPECT_EQ(named.front(), first);
  EXPECT_TRUE(names(named, also));
}

/// A delay named first and no rate dependence; the extended model holds `samples` of delay and
/// predicts the second record better than the baseline.
void expect_a_delay_and_no_rate_law(const Outcome& o, std::size_t samples) {
  const std::vector<hc::Cause> named = named_causes(o.diagnosis);
  ASSERT_FALSE(named.empty());
  EXPECT_EQ(named.front(), hc::Cause::kDelay);
  EXPECT_FALSE(names(named, hc::Cause::kRateDependence));
  EXPECT_EQ(o.diagnosis.extended.delay_samples(), samples);
  EXPECT_LE(o.ratio, kMaxRatio) << "extended / baseline rms on the second record";
}

/// The cause's statistic was read again on what the delay named first leaves.
void expect_read_again_behind_the_delay(const hc::Diagnosis& d, hc::Cause cause) {
  const hc::CandidateReport* c = d.candidate(cause);
  ASSERT_NE(c, nullptr);
  EXPECT_NE(c->evidence.find("on what the model holding delay"), std::string::npos) << c->evidence;
}

}  // namespace

// A delay and a rate-widened loop both lag the output, and are told apart both ways: relays
// whose thresholds widen with |du/dt| are named rate dependence and not delay; a pure delay is
// named delay and not rate dependence.
TEST(DiagnosisSeveralCauses, TellsARateWidenedLoopFromADelay) {
  for (const double fs : {1000.0, 5000.0}) {
    HiddenCase rate{hc::Cause::kRateDependence, fs, 1020};
    rate.widening_thresholds = true;
    const auto [r, rate_trace] = diagnose_ranked(rate);
    SCOPED_TRACE(rate_trace);
    const std::vector<hc::Cause> named_rate = named_causes(r.diagnosis);
    EXPECT_TRUE(names(named_rate, hc::Cause::kRateDependence));
    EXPECT_FALSE(names(named_rate, hc::Cause::kDelay));
    const auto [d, delay_trace] = diagnose_ranked({hc::Cause::kDelay, fs, 106});
    SCOPED_TRACE(delay_trace);
    const std::vector<hc::Cause> named_delay = named_causes(d.diagnosis);
    EXPECT_TRUE(names(named_delay, hc::Cause::kDelay));
    EXPECT_FALSE(names(named_delay, hc::Cause::kRateDependence));
  }
}

// A delay and a resonance hidden at once: both are named, ranked by their held-out gain, and
// both are in the extended model, which predicts the second record better. The Preisach base's
// shape may be named beside them (see the file's header), nothing else.
TEST(DiagnosisSeveralCauses, NamesAndRanksTwoHiddenEffects) {
  const auto [o, trace] =
      diagnose_ranked({hc::Cause::kDelay, 1000.0, 106, false, 0.0, 0.0, hc::Cause::kDynamics});
  SCOPED_TRACE(trace);
  std::vector<hc::Cause> named = named_causes(o.diagnosis);
  EXPECT_TRUE(names(named, hc::Cause::kDelay));
  EXPECT_TRUE(names(named, hc::Cause::kDynamics));
  std::erase_if(named, [](hc::Cause n) {
    return n == hc::Cause::kDelay || n == hc::Cause::kDynamics || n == hc::Cause::kAsymmetry;
  });
  EXPECT_TRUE(named.empty());
  EXPECT_GT(o.diagnosis.extended.delay_samples(), 0u);
  EXPECT_TRUE(o.diagnosis.extended.dynamics().has_value());
  EXPECT_LE(o.ratio, kMaxRatio) << "extended / baseline rms on the second record";
}

// A one-sample delay beside a 49 Hz mode at 200 Hz: the resonance named first is fitted off the
// measured peak, its phase standing in for the delay (35 Hz, damping 0.46). Found again at the
// delay, it goes back to the peak, and the delay is named beside it.
TEST(DiagnosisSeveralCauses, NamesADelayWhosePhaseTheResonanceHeld) {
  HiddenCase c{hc::Cause::kDelay, 200.0, 1066};
  c.also = hc::Cause::kDynamics;
  const auto [o, trace] = diagnose_ranked(c);
  SCOPED_TRACE(trace);
  const std::vector<hc::Cause> named = named_causes(o.diagnosis);
  EXPECT_TRUE(names(named, hc::Cause::kDelay));
  EXPECT_TRUE(names(named, hc::Cause::kDynamics));
  EXPECT_FALSE(names(named, hc::Cause::kRateDependence));
  EXPECT_EQ(o.diagnosis.extended.delay_samples(), 1u);
  ASSERT_TRUE(o.diagnosis.extended.dynamics().has_value());
  EXPECT_NEAR(o.diagnosis.extended.dynamics()->natural_frequency_hz, 49.3, 0.1 * 49.3);
  EXPECT_LE(o.ratio, kMaxRatio) << "extended / baseline rms on the second record";
}

// A 1-sample delay at 100 Hz (10 ms) and a linear thresholds law without a filter both lag every
// ramp: alone (seed 3041) the law gained 1.80x and the delay 1.79x. Right after the input's
// reversals they differ, the delay carrying the output on, the law holding it; ordered by their
// errors there, the delay is named and the law is not. Beside a widening law (seed 4065) the
// delay goes first the same way, and the law is named on top of it.
TEST(DiagnosisSeveralCauses, TellsADelayFromARateLawAfterTheReversals) {
  {
    const auto [o, trace] = diagnose_ranked({hc::Cause::kDelay, 100.0, 3041});
    SCOPED_TRACE(trace);
    expect_a_delay_and_no_rate_law(o, 1);
    EXPECT_TRUE(ordered_after_reversals(o.diagnosis));
  }
  {
    const auto [o, trace] = diagnose_ranked(
        with_widening_law(hc::Cause::kRateDependence, 100.0, 4065, hc::Cause::kDelay));
    SCOPED_TRACE(trace);
    expect_named_first_and(named_causes(o.diagnosis), hc::Cause::kDelay,
                           hc::Cause::kRateDependence);
    EXPECT_TRUE(ordered_after_reversals(o.diagnosis));
    EXPECT_EQ(o.diagnosis.extended.delay_samples(), 1u);
    EXPECT_LE(o.ratio, kMaxRatio) << "extended / baseline rms on the second record";
  }
}

// Thresholds widening with the rate beside a 1-sample delay at 500 Hz: the delay, named first and
// found on the baseline, takes the widening's lag too (2 samples), and the law added on top of it
// gained 1.04x. Tried on a sample less, the law is named, and the extended model holds the
// truth's delay.
TEST(DiagnosisSeveralCauses, NamesAWideningLawWhoseLagTheDelayTook) {
  const auto [o, trace] = diagnose_ranked(
      with_widening_law(hc::Cause::kRateDependence, 500.0, 4067, hc::Cause::kDelay));
  SCOPED_TRACE(trace);
  const std::vector<hc::Cause> named = named_causes(o.diagnosis);
  expect_named_first_and(named, hc::Cause::kDelay, hc::Cause::kRateDependence);
  EXPECT_EQ(o.diagnosis.extended.delay_samples(), 1u);
  EXPECT_NE(o.diagnosis.extended_description.find("the delay found again with it at 1 samples"),
            std::string::npos)
      << o.diagnosis.extended_description;
  EXPECT_LE(o.ratio, kMaxRatio) << "extended / baseline rms on the second record";
}

// Thresholds widening with the rate beside a lightly damped mode at 2 kHz (122 Hz, damping 0.044;
// 151 Hz, 0.023): the mode, named first, is fitted on its measured peak, but without a rate law
// its phase stands in for some of the widening, and the law added on top of it gained 1.05-1.09x.
// With the mode projected again beside the law, the law is named, joins the extended model, and
// the mode stays on the truth's.
TEST(DiagnosisSeveralCauses, NamesAWideningLawBesideALightlyDampedMode) {
  for (const auto& [seed, mode_hz] :
       {std::pair<std::uint64_t, double>{3069, 121.7}, {4069, 150.6}}) {
    const auto [o, trace] = diagnose_ranked(
        with_widening_law(hc::Cause::kDynamics, 2000.0, seed, hc::Cause::kRateDependence));
    SCOPED_TRACE(trace);
    const std::vector<hc::Cause> named = named_causes(o.diagnosis);
    expect_named_first_and(named, hc::Cause::kDynamics, hc::Cause::kRateDependence);
    EXPECT_FALSE(names(named, hc::Cause::kDelay));
    const auto& parts = o.diagnosis.extended_parts;
    EXPECT_NE(std::find(parts.begin(), parts.end(), "rate_dependence"), parts.end());
    ASSERT_TRUE(o.diagnosis.extended.dynamics().has_value());
    EXPECT_NEAR(o.diagnosis.extended.dynamics()->natural_frequency_hz, mode_hz, 0.05 * mode_hz);
    EXPECT_LE(o.ratio, kMaxRatio) << "extended / baseline rms on the second record";
  }
}

// A slow drift beside a delay at 1 kHz: on the baseline's residual the delay's error on every
// move hides the drift (its statistic below the threshold, in 9 of 12 such draws); read again on
// what the delay leaves, it is named beside it, and not fitted into the saved model.
TEST(DiagnosisSeveralCauses, NamesADriftTheDelayHidFromTheBaseline) {
  for (const std::uint64_t seed : {3001, 3003}) {
    HiddenCase c{hc::Cause::kDelay, 1000.0, seed};
    c.also = hc::Cause::kDrift;
    const auto [o, trace] = diagnose_ranked(c);
    SCOPED_TRACE(trace);
    const std::vector<hc::Cause> named = named_causes(o.diagnosis);
    expect_named_first_and(named, hc::Cause::kDelay, hc::Cause::kDrift);
    expect_read_again_behind_the_delay(o.diagnosis, hc::Cause::kDrift);
    const hc::CandidateReport* drift = o.diagnosis.candidate(hc::Cause::kDrift);
    ASSERT_NE(drift, nullptr);
    EXPECT_GE(drift->statistic, drift->threshold);
    EXPECT_GT(o.diagnosis.extended.delay_samples(), 0u);
  }
}

// A logarithmic creep at 10 kHz behind the loop's shape: on the baseline's residual neither its
// hold profile (0.14) nor the drift's time profile (0.11) is significant; on what the shape
// leaves both are (0.29 and 0.39: the creep's slow part looks like a drift). Read again there,
// the creep goes before the drift and is named, and the drift then adds too little to be.
TEST(DiagnosisSeveralCauses, ReadsACreepAgainBeforeADrift) {
  const auto [o, trace] = diagnose_ranked({hc::Cause::kCreep, 10000.0, 3031});
  SCOPED_TRACE(trace);
  const std::vector<hc::Cause> named = named_causes(o.diagnosis);
  EXPECT_TRUE(names(named, hc::Cause::kCreep));
  EXPECT_FALSE(names(named, hc::Cause::kDrift));
}

// Thresholds widening with the rate beside a 1-sample delay at 100 Hz: on the baseline's
// residual the delay's error on every move hides the loop's shape (its level statistic 0.02-0.03),
// and added to the delay alone the rate law gains 1.07-1.08x, the shape's error left in both.
// The shape, read again on what the delay leaves, joins first; the rate effect is named on top.
TEST(DiagnosisSeveralCauses, ReadsTheShapeAgainBeforeTheCausesAfterTheFirst) {
  for (const std::uint64_t seed : {1065, 2065}) {
    const auto [o, trace] = diagnose_ranked(
        with_widening_law(hc::Cause::kRateDependence, 100.0, seed, hc::Cause::kDelay));
    SCOPED_TRACE(trace);
    const std::vector<hc::Cause> named = named_causes(o.diagnosis);
    expect_named_first_and(named, hc::Cause::kDelay, hc::Cause::kRateDependence);
    expect_read_again_behind_the_delay(o.diagnosis, hc::Cause::kAsymmetry);
    const auto& parts = o.diagnosis.extended_parts;
    ASSERT_GE(parts.size(), 2u);
    EXPECT_EQ(parts[1], "asymmetry");
    EXPECT_EQ(o.diagnosis.causes.back().cause, hc::Cause::kAsymmetry);
    std::vector<hc::Cause> others = named;
    std::erase_if(others, [](hc::Cause n) {
      return n == hc::Cause::kDelay || n == hc::Cause::kRateDependence ||
             n == hc::Cause::kAsymmetry;
    });
    EXPECT_TRUE(others.empty());
  }
}

// A 35-sample delay at 20 kHz, found on the baseline (which misses the shape) a sample short: with
// the shape joined, a rate law took the lag left (1.46x added). Found again on top of the shape,
// the delay is the truth's, and no rate dependence is named.
TEST(DiagnosisSeveralCauses, FindsTheDelayAgainOnTopOfTheShape) {
  const auto [o, trace] = diagnose_ranked({hc::Cause::kDelay, 20000.0, 4048});
  SCOPED_TRACE(trace);
  expect_a_delay_and_no_rate_law(o, 35);
}

// The same actuator with the delay alone: one cause is named (beside the Preisach base's shape,
// which the delay hid from the baseline's residual), and the resonance candidate, whose extension
// also lowers the held-out error on its own, says why it is not.
TEST(DiagnosisSeveralCauses, NamesOneCauseForOneHiddenEffect) {
  const auto [o, trace] = diagnose_ranked({hc::Cause::kDelay, 1000.0, 106});
  SCOPED_TRACE(trace);
  std::vector<hc::Cause> named = named_causes(o.diagnosis);
  std::erase(named, hc::Cause::kAsymmetry);
  EXPECT_EQ(named, std::vector<hc::Cause>{hc::Cause::kDelay});
  const hc::CandidateReport* dynamics = o.diagnosis.candidate(hc::Cause::kDynamics);
  ASSERT_NE(dynamics, nullptr);
  EXPECT_GE(dynamics->gain, 1.2);
  EXPECT_FALSE(dynamics->named);
}

// Off-centre relays: the rate-dependent PI's extension is significant, carries over and gains
// min_gain on its own, as the modified PI's does more, but added to the modified PI it explains
// nothing the noise would not: it is within the noise of asymmetry, reported so and not named.
TEST(DiagnosisSeveralCauses, DoesNotNameACandidateWithinTheNoiseOfAStrongerOne) {
  const auto [o, trace] = diagnose_ranked({hc::Cause::kAsymmetry, 1000.0, 502});
  SCOPED_TRACE(trace);
  EXPECT_EQ(named_causes(o.diagnosis), std::vector<hc::Cause>{hc::Cause::kAsymmetry});
  int within = 0;
  for (const hc::CandidateReport& k : o.diagnosis.candidates) {
    if (k.named || !k.significant || !k.carries_over || k.gain < 1.2) continue;
    // Would be named but for the noise rule.
    EXPECT_EQ(k.not_named.rfind("within the noise of asymmetry", 0), 0u) << k.not_named;
    ++within;
  }
  EXPECT_GE(within, 1) << "no candidate here is left out by the noise rule alone";
}

// ------------------------------------------------------------------------ several records

namespace {

// One record of `config`: a full-range sine (0 .. 150 V) at one frequency, from rest at 0.
Record sine_record(const hs::SimulatedActuatorConfig& config, double fs, double frequency_hz,
                   double seconds, std::uint64_t noise_seed) {
  hs::SimulatedActuatorConfig c = config;
  c.sensor_noise.seed = noise_seed;
  hs::SimulatedActuator actuator(c, 1.0 / fs);
  hs::Excitation x;
  x.dt_s = 1.0 / fs;
  const auto n = static_cast<std::size_t>(seconds * fs);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    x.samples.push_back(75.0 - 75.0 * std::cos(2.0 * std::numbers::pi * frequency_hz * t));
  }
  return run(actuator, x);
}

// A symmetric PI whose play weights change with du/dt (the modified-PI truth with one identity
// dead zone and its play-weight law): a rate law the diagnosis fits, for the test of how it treats
// several records.
hs::SimulatedActuatorConfig rate_dependent_pi(std::uint64_t seed, double fs) {
  std::mt19937_64 rng(seed);
  hs::SimulatedActuatorConfig c = hs::SimulatedActuatorConfig::modified_pi_truth();
  c.creep.enabled = false;
  c.dynamics.enabled = false;
  c.thermal_drift.enabled = false;
  const int n = static_cast<int>(uniform(rng, 6, 13));
  std::vector<double> r{0.0};
  while (static_cast<int>(r.size()) < n) {
    const double v = uniform(rng, 2.0, 72.0);
    if (std::all_of(r.begin(), r.end(), [&](double x) { return std::abs(x - v) > 2.0; }))
      r.push_back(v);
  }
  std::sort(r.begin(), r.end());
  std::vector<double> w{uniform(rng, 0.12, 0.25)};
  for (int i = 1; i < n; ++i) w.push_back(uniform(rng, 0.01, 0.04));
  hc::PiModel loop(hc::PiParameters{r, w, 0.0});
  loop.reset(0.0);
  loop.step(150.0);
  const double bottom = loop.step(0.0);
  const double scale = 40.0 / (loop.step(150.0) - bottom);
  for (double& v : w) v *= scale;
  c.hysteresis.play_thresholds_v = r;
  c.hysteresis.play_weights_um_per_v = w;
  c.hysteresis.play_offset_um = -bottom * scale;
  c.hysteresis.dead_zone_thresholds_um = {0.0};
  c.hysteresis.dead_zone_weights = {1.0};
  c.hysteresis.dead_zone_center_um = 20.0;
  c.sensor_noise.rms_um = uniform(rng, 0.003, 0.02);
  // Weights up by alpha at the excitation's fastest smooth rate (0.8 of the range).
  const double fastest = std::min(10.0, fs / 20.0);
  c.rate_dependence.enabled = true;
  c.rate_dependence.max_rate_v_per_s =
      1.2 * std::max(2.0 * std::numbers::pi * fastest * 0.4 * 150.0, 300.0);
  const double alpha = uniform(rng, 0.2, 0.6);
  c.rate_dependence.rate_coefficients.assign(w.size(), 0.0);
  double cumulative = 0.0;
  for (std::size_t i = 0; i < w.size(); ++i) {
    cumulative += w[i];
    c.rate_dependence.rate_coefficients[i] = alpha * static_cast<double>(i) /
                                             static_cast<double>(w.size() - 1) * cumulative /
                                             c.rate_dependence.max_rate_v_per_s;
  }
  return c;
}

std::vector<hc::RecordView> views(const std::vector<Record>& records) {
  std::vector<hc::RecordView> v;
  for (std::size_t i = 0; i < records.size(); ++i) {
    v.push_back({records[i].t, records[i].u, records[i].y, "run " + std::to_string(i + 1)});
  }
  return v;
}

}  // namespace

// Rate dependence that only a set of records shows: each record is one sine at one frequency, so
// every input level is crossed at one rate per direction and a rate-independent model absorbs
// the rate law into its loop; across records at 1, 3 and 8 Hz the same levels are crossed at
// different rates. Random rate-dependent PIs (the rate law the diagnosis fits: what is under test
// is the leave-one-record-out check): no single record names rate dependence, the set does, and
// the rate law fitted on two records predicts the third, left out whole, better than the baseline
// does.
TEST(DiagnosisSeveralRecords, NamesRateDependenceSeenOnlyAcrossRecords) {
  const int cases = long_tests() ? 8 : 2;
  for (int i = 0; i < cases; ++i) {
    const HiddenCase hidden{hc::Cause::kRateDependence, 1000.0,
                            301 + static_cast<std::uint64_t>(i)};
    const hs::SimulatedActuatorConfig config = rate_dependent_pi(hidden.seed, hidden.fs);
    std::vector<Record> records;
    const double frequencies[] = {1.0, 3.0, 8.0};
    for (std::size_t j = 0; j < 3; ++j) {
      records.push_back(sine_record(config, hidden.fs, frequencies[j], 6.0, 40 + j));
    }
    SCOPED_TRACE(name_of(hidden));
    for (std::size_t j = 0; j < 3; ++j) {
      const hc::Diagnosis single = hc::diagnose(records[j].t, records[j].u, records[j].y);
      EXPECT_NE(single.cause, hc::Cause::kRateDependence)
          << frequencies[j] << " Hz alone: " << single.verdict;
    }
    const std::vector<hc::RecordView> set = views(records);
    const hc::Diagnosis together = hc::diagnose(set);
    Outcome o;
    o.diagnosis = together;
    o.named = together.cause;
    SCOPED_TRACE(summary(o));
    EXPECT_EQ(together.cause, hc::Cause::kRateDependence) << together.verdict;
    ASSERT_EQ(together.records.size(), 3u);
    const hc::CandidateReport* rate = together.candidate(hc::Cause::kRateDependence);
    ASSERT_NE(rate, nullptr);
    ASSERT_EQ(rate->left_out.size(), 3u);
    EXPECT_TRUE(rate->carries_over);
    EXPECT_GT(rate->left_out[1].gain, 1.5) << "3 Hz left out, fitted on 1 and 8 Hz";
    std::printf("%s: named %s, left-out gains %.2f %.2f %.2f\n", name_of(hidden).c_str(),
                std::string(hc::to_string(together.cause)).c_str(), rate->left_out[0].gain,
                rate->left_out[1].gain, rate->left_out[2].gain);
  }
}

// A set with a bad record, or records at different sample rates, is refused with the record
// named.
TEST(DiagnosisSeveralRecords, RefusesABadSetNamingTheRecord) {
  const HiddenData d = make_hidden({hc::Cause::kNone, 500.0, 311});
  const Record a = sine_record(d.config, 500.0, 1.0, 4.0, 1);
  std::vector<double> t = a.t, u = a.u, y = a.y;
  const std::vector<double> short_t(t.begin(), t.begin() + 100);
  const std::vector<double> short_u(u.begin(), u.begin() + 100),
      short_y(y.begin(), y.begin() + 100);
  const std::vector<hc::RecordView> bad{{t, u, y, "a.csv"}, {short_t, short_u, short_y, "b.csv"}};
  try {
    (void)hc::diagnose(bad);
    ADD_FAILURE() << "a short record was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("b.csv: too few samples", 0), 0u) << e.what();
  }
  const Record other_rate = sine_record(d.config, 1000.0, 1.0, 4.0, 2);
  const std::vector<hc::RecordView> mixed{{t, u, y, "a.csv"},
                                          {other_rate.t, other_rate.u, other_rate.y, "c.csv"}};
  try {
    (void)hc::diagnose(mixed);
    ADD_FAILURE() << "records at 500 Hz and 1 kHz were diagnosed together";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("c.csv: sample period 1 ms differs from a.csv's 2 ms"),
              std::string::npos)
        << e.what();
  }
}

// ------------------------------------------------------------------------ the randomised sweep

// A repeated random-phase multisine (the excitation of system-identification benches) through a
// PI with a lightly damped resonance: the baseline's residual has content up to the Nyquist
// frequency, so its second differences are no noise estimate; the output's period-to-period
// difference is.
TEST(Diagnosis, EstimatesTheNoiseFromTheOutputWhenTheInputRepeats) {
  const HiddenData d = make_hidden({hc::Cause::kNone, 1000.0, 301});
  hs::SimulatedActuatorConfig c = d.config;
  c.dynamics.enabled = true;
  c.dynamics.natural_frequencies_hz = {3000.0};
  c.dynamics.damping_ratios = {0.05};
  c.dynamics.mode_gains = {1.0};
  c.sensor_noise.rms_um = 0.01;
  const double dt = 1.0 / 20000.0;
  const std::size_t period = 20000, repeats = 4;
  std::mt19937_64 rng(302);
  std::vector<double> one(period, 0.0);
  for (std::size_t j = 1; j <= period * 2 / 5; j += 7) {
    const double phase = uniform(rng, 0.0, 2.0 * std::numbers::pi);
    for (std::size_t k = 0; k < period; ++k) {
      one[k] += std::cos(2.0 * std::numbers::pi * static_cast<double>(j * k) /
                             static_cast<double>(period) +
                         phase);
    }
  }
  const auto [lo, hi] = std::minmax_element(one.begin(), one.end());
  const double low = *lo, span = *hi - *lo;
  hs::Excitation x;
  x.dt_s = dt;
  for (std::size_t i = 0; i < repeats; ++i) {
    for (const double v : one) x.samples.push_back(150.0 * (v - low) / span);
  }
  hs::SimulatedActuator actuator(c, dt);
  const Record r = run(actuator, x);
  const hc::Diagnosis periodic = hc::diagnose(r.t, r.u, r.y);
  EXPECT_EQ(periodic.input_period, period);
  EXPECT_NEAR(periodic.noise_rms, 0.01, 0.002) << periodic.noise_source;
  EXPECT_NE(periodic.noise_source.find("period"), std::string::npos);

  // The identification excitation does not repeat: the residual's estimate stands.
  const hc::Diagnosis once = hc::diagnose(d.first.t, d.first.u, d.first.y);
  EXPECT_EQ(once.input_period, 0U);
  EXPECT_NEAR(once.noise_rms, d.config.sensor_noise.rms_um, 0.25 * d.config.sensor_noise.rms_um);
}

// A record with one loop only (a full-range triangle, as the measured NTU identification run)
// cannot show how the actuator behaves on minor loops: the report says so; the identification
// excitation, with nested minor loops, does not get the note.
TEST(Diagnosis, NotesARecordWithOneLoopOnly) {
  const HiddenData d = make_hidden({hc::Cause::kNone, 1000.0, 321});
  hs::Excitation x;
  x.dt_s = 1e-3;
  for (std::size_t k = 0; k < 20000; ++k) {
    const double phase = std::fmod(static_cast<double>(k) * 1e-3, 1.0);
    x.samples.push_back(150.0 * (phase < 0.5 ? 2.0 * phase : 2.0 - 2.0 * phase));
  }
  hs::SimulatedActuator actuator(d.config, x.dt_s);
  const Record r = run(actuator, x);
  auto one_loop_note = [](const hc::Diagnosis& diagnosis) {
    return std::any_of(diagnosis.notes.begin(), diagnosis.notes.end(), [](const std::string& s) {
      return s.find("every reversal of the input is at its extremes") != std::string::npos;
    });
  };
  EXPECT_TRUE(one_loop_note(hc::diagnose(r.t, r.u, r.y)));
  EXPECT_FALSE(one_loop_note(hc::diagnose(d.first.t, d.first.u, d.first.y)));
}

// A record whose input reaches both its extremes late (its first 30 % wanders between 60 and
// 90 V): the start is not scored, and the drift fitted on the rest holds its value there instead
// of swinging where no fitted sample constrains it.
TEST(Diagnosis, ADriftIsNotFittedIntoALongUnscoredStart) {
  const HiddenData d = make_hidden({hc::Cause::kDrift, 1000.0, 1052});
  hs::Excitation x;
  x.dt_s = 1e-3;
  const std::size_t rest = d.first.u.size(), start = rest * 3 / 7;  // 30 % of the whole
  for (std::size_t k = 0; k < start; ++k) {
    x.samples.push_back(75.0 + 15.0 * std::sin(2.0 * M_PI * static_cast<double>(k) * 1e-3));
  }
  x.samples.insert(x.samples.end(), d.first.u.begin(), d.first.u.end());
  hs::SimulatedActuator actuator(d.config, x.dt_s);
  const Record r = run(actuator, x);
  const hc::Diagnosis diagnosis = hc::diagnose(r.t, r.u, r.y);
  EXPECT_GE(diagnosis.split.skipped, start * 4 / 7) << diagnosis.split.describe(1e-3);
  const hc::CandidateReport* drift = diagnosis.candidate(hc::Cause::kDrift);
  ASSERT_NE(drift, nullptr);
  ASSERT_EQ(drift->drift.size(), r.y.size());
  const auto [lo, hi] = std::minmax_element(drift->drift.begin(), drift->drift.end());
  const auto [ylo, yhi] = std::minmax_element(r.y.begin(), r.y.end());
  EXPECT_TRUE(std::isfinite(*lo) && std::isfinite(*hi));
  EXPECT_LT(*hi - *lo, 0.1 * (*yhi - *ylo)) << drift->extension;
}

// A second actuator, driven by an input the record does not have, adds twice its motion to the
// output (a multi-axis stage seen through one axis): the diagnosis says so instead of forcing a
// cause.
TEST(Diagnosis, SaysWhenAnInputNotInTheRecordDrivesTheOutput) {
  const HiddenData a = make_hidden({hc::Cause::kNone, 1000.0, 311});
  const HiddenData b = make_hidden({hc::Cause::kNone, 1000.0, 312});
  const std::size_t n = std::min(a.first.u.size(), b.second.u.size());
  Record r;
  r.t.assign(a.first.t.begin(), a.first.t.begin() + static_cast<std::ptrdiff_t>(n));
  r.u.assign(a.first.u.begin(), a.first.u.begin() + static_cast<std::ptrdiff_t>(n));
  const std::vector<double> own(a.first.y.begin(),
                                a.first.y.begin() + static_cast<std::ptrdiff_t>(n));
  for (std::size_t k = 0; k < n; ++k) r.y.push_back(own[k] + 2.0 * b.second.y[k]);
  auto unexplained_note = [](const hc::Diagnosis& d) {
    return std::any_of(d.notes.begin(), d.notes.end(), [](const std::string& s) {
      return s.find("something not in this record") != std::string::npos;
    });
  };

  const hc::Diagnosis coupled = hc::diagnose(r.t, r.u, r.y);
  SCOPED_TRACE(coupled.verdict);
  EXPECT_LT(coupled.coherent_share, 0.5);
  EXPECT_TRUE(unexplained_note(coupled));

  const hc::Diagnosis alone = hc::diagnose(r.t, r.u, own);
  EXPECT_GT(alone.coherent_share, 0.9);
  EXPECT_FALSE(unexplained_note(alone));
}

TEST(DiagnosisHiddenEffect, RandomisedSweepConfusionTable) {
  if (!long_tests()) GTEST_SKIP() << "set HYSTBENCH_LONG_TESTS=1 for the 72-case sweep";
  const double rates[] = {100, 200, 500, 1000, 2000, 5000, 10000, 20000};
  const std::vector<hc::Cause> causes = {
      hc::Cause::kNone,     hc::Cause::kAsymmetry, hc::Cause::kRateDependence, hc::Cause::kCreep,
      hc::Cause::kDynamics, hc::Cause::kDelay,     hc::Cause::kDrift};
  // HYSTBENCH_SWEEP_SEED draws another set of cases.
  const char* base = std::getenv("HYSTBENCH_SWEEP_SEED");
  std::uint64_t seed = base != nullptr ? std::strtoull(base, nullptr, 10) : 1000;
  // HYSTBENCH_SWEEP_CAUSE runs the cases that hide that cause only (seeds as in the whole sweep).
  const char* only = std::getenv("HYSTBENCH_SWEEP_CAUSE");
  const bool verbose = std::getenv("HYSTBENCH_SWEEP_VERBOSE") != nullptr;  // every case's report
  std::vector<HiddenCase> cases;
  for (const hc::Cause cause : causes) {
    bool widening = false;
    for (const double fs : rates) {
      // Rate dependence alternates its two mechanisms: a switching front, widening thresholds.
      cases.push_back({cause, fs, ++seed});
      cases.back().widening_thresholds = cause == hc::Cause::kRateDependence && widening;
      widening = !widening;
    }
  }
  for (const double fs : rates) cases.push_back({hc::Cause::kDrift, fs, ++seed, true});
  // Two effects at once, one pair per sampling rate.
  const std::pair<hc::Cause, hc::Cause> pairs[] = {
      {hc::Cause::kRateDependence, hc::Cause::kDelay},
      {hc::Cause::kDelay, hc::Cause::kDynamics},
      {hc::Cause::kRateDependence, hc::Cause::kDelay},
      {hc::Cause::kAsymmetry, hc::Cause::kDelay},
      {hc::Cause::kDynamics, hc::Cause::kRateDependence},
      {hc::Cause::kCreep, hc::Cause::kDelay},
      {hc::Cause::kAsymmetry, hc::Cause::kRateDependence},
      {hc::Cause::kDelay, hc::Cause::kDrift}};
  for (std::size_t i = 0; i < std::size(pairs); ++i) {
    HiddenCase c{pairs[i].first, rates[i], ++seed};
    c.also = pairs[i].second;
    c.widening_thresholds = i % 2 == 0;
    cases.push_back(c);
  }
  if (only != nullptr) {
    std::erase_if(cases, [&](const HiddenCase& c) {
      return hc::to_string(c.cause) != only && hc::to_string(c.also) != only;
    });
  }
  std::map<std::pair<int, int>, int> confusion;
  // Per cause: named anywhere in a case (random walks aside) that does not hide it. The shape
  // (asymmetry) is the Preisach base's own and may be named in any case.
  std::map<int, int> named_not_hidden;
  constexpr int kWalkRow = 100;  // confusion row of the random-walk drifts
  std::vector<double> walk_ratios;
  std::map<int, std::vector<double>> ratios, raw_ratios;
  std::map<int, std::pair<int, int>> recall;  // per hidden cause: named anywhere, cases
  int wrong = 0, count = 0, bad_ratio = 0, combined = 0, both_named = 0, rate_as_delay = 0,
      delay_as_rate = 0;
  double slowest = 0.0;
  std::size_t slowest_samples = 0;
  for (const HiddenCase& c : cases) {
    const hc::Cause cause = c.cause;
    const HiddenData d = make_hidden(c);
    const Outcome o = diagnose_case(d);
    ++count;
    auto named_anywhere = [&](hc::Cause h) {
      return std::any_of(o.diagnosis.causes.begin(), o.diagnosis.causes.end(),
                         [&](const hc::NamedCause& n) { return n.cause == h; });
    };
    if (!c.random_walk) {
      for (const hc::NamedCause& n : o.diagnosis.causes) {
        const bool hidden = n.cause == cause || n.cause == c.also;
        if (!hidden && n.cause != hc::Cause::kAsymmetry)
          ++named_not_hidden[static_cast<int>(n.cause)];
      }
      for (const hc::Cause h : {cause, c.also}) {
        if (h == hc::Cause::kNone) continue;
        auto& [hit, n] = recall[static_cast<int>(h)];
        hit += named_anywhere(h) ? 1 : 0;
        ++n;
      }
    }
    if (c.also != hc::Cause::kNone) {
      ++combined;
      const bool both = named_anywhere(cause) && named_anywhere(c.also);
      both_named += both ? 1 : 0;
      std::printf("%-52s %-6s named", name_of(c).c_str(), both ? "both" : "MISSED");
      for (const auto& n : o.diagnosis.causes) {
        std::printf(" %s (%.2f)", std::string(hc::to_string(n.cause)).c_str(), n.gain);
      }
      std::printf("  %.2f s\n", o.seconds);
      if (!both) std::printf("  truth: %s\n%s", d.truth.c_str(), summary(o).c_str());
      std::fflush(stdout);
      continue;
    }
    ++confusion[{c.random_walk ? kWalkRow : static_cast<int>(cause), static_cast<int>(o.named)}];
    if (cause == hc::Cause::kRateDependence && named_anywhere(hc::Cause::kDelay)) ++rate_as_delay;
    if (cause == hc::Cause::kDelay && named_anywhere(hc::Cause::kRateDependence)) ++delay_as_rate;
    // With nothing hidden, the base's own shape may be named (see the file's header).
    const bool shape_only = cause == hc::Cause::kNone && o.named == hc::Cause::kAsymmetry;
    const bool ratio_checked = (cause != hc::Cause::kNone || shape_only) && !c.random_walk;
    if (ratio_checked) ratios[static_cast<int>(cause)].push_back(o.ratio);
    if (ratio_checked) raw_ratios[static_cast<int>(cause)].push_back(o.raw_ratio);
    if (c.random_walk) walk_ratios.push_back(o.ratio);
    const bool ok =
        (o.named == cause || shape_only) && (!ratio_checked || o.ratio <= max_ratio(cause));
    // Reported in their own rows, not asserted: random walks, the harder class beyond the
    // causes (a walk's fast part is not a slow drift), and rate dependence, whose weaker cases
    // gain less than the naming asks beside the loop's shape the baseline misses (behind a
    // switching front or with widening thresholds alike). That a rate effect is never called
    // delay, nor a delay rate dependence, is asserted.
    const bool reported = c.random_walk || cause == hc::Cause::kRateDependence;
    if (!ok && !reported) ++wrong;
    if (ratio_checked && !reported && o.ratio > max_ratio(cause)) ++bad_ratio;
    if (o.seconds > slowest) slowest = o.seconds, slowest_samples = o.samples;
    std::printf("%-52s %-6s named %-16s ratio %.3f (raw %.3f) gain %7.2f  %.2f s / %zu samples\n",
                name_of(c).c_str(), ok ? "ok" : "WRONG",
                std::string(hc::to_string(o.named)).c_str(), o.ratio, o.raw_ratio, o.gain,
                o.seconds, o.samples);
    if (!ok || verbose) std::printf("  truth: %s\n%s", d.truth.c_str(), summary(o).c_str());
    if (verbose) {  // each candidate's own model on the second record, against the baseline
      const Record& r2 = d.second_without_drift;
      const double dt2 = r2.t[1] - r2.t[0];
      const double base = hc::validate_model(o.diagnosis.baseline, r2.u, r2.y, dt2).rmse;
      std::printf("  on the second record:");
      for (const hc::CandidateReport& cr : o.diagnosis.candidates) {
        std::printf(" %s %.3f", std::string(hc::to_string(cr.cause)).c_str(),
                    hc::validate_model(cr.model, r2.u, r2.y, dt2).rmse / base);
      }
      std::printf("\n");
    }
    std::fflush(stdout);
  }
  std::printf("\nconfusion of the single effects (rows: hidden, columns: named), %d cases\n%-16s",
              count - combined, "");
  for (const hc::Cause n : causes) std::printf("%9.8s", std::string(hc::to_string(n)).c_str());
  std::printf("\n");
  std::vector<std::pair<std::string, int>> rows;
  rows.reserve(causes.size() + 1);
  for (const hc::Cause h : causes) rows.emplace_back(hc::to_string(h), static_cast<int>(h));
  rows.emplace_back("drift (walk)", kWalkRow);
  for (const auto& [label, row] : rows) {
    std::printf("%-16s", label.c_str());
    for (const hc::Cause n : causes) std::printf("%9d", confusion[{row, static_cast<int>(n)}]);
    std::printf("\n");
  }
  std::printf("\nrecall per hidden cause (named anywhere in causes[], single and combined):\n");
  for (const auto& [cause, hits] : recall) {
    std::printf("  %-16s %d / %d (%.0f %%)\n",
                std::string(hc::to_string(static_cast<hc::Cause>(cause))).c_str(), hits.first,
                hits.second, 100.0 * hits.first / std::max(hits.second, 1));
  }
  std::printf("named where not hidden (random walks aside, the shape allowed):");
  for (const auto& [cause, n] : named_not_hidden) {
    std::printf(" %s %d", std::string(hc::to_string(static_cast<hc::Cause>(cause))).c_str(), n);
  }
  std::printf("\n");
  std::printf(
      "both effects named in %d of %d combined cases; rate dependence called delay %d, delay "
      "called rate dependence %d\n",
      both_named, combined, rate_as_delay, delay_as_rate);
  std::printf(
      "\nextended / baseline rms on the second record (median, worst; raw: from its first "
      "sample):\n");
  for (auto& [cause, v] : ratios) {
    std::vector<double>& raw = raw_ratios[cause];
    std::sort(v.begin(), v.end());
    std::sort(raw.begin(), raw.end());
    std::printf("  %-16s %.3f  %.3f   raw %.3f  %.3f\n",
                std::string(hc::to_string(static_cast<hc::Cause>(cause))).c_str(), v[v.size() / 2],
                v.back(), raw[raw.size() / 2], raw.back());
  }
  // A fitted resonance carries over to another record of the same actuator.
  if (const auto& dyn = ratios[static_cast<int>(hc::Cause::kDynamics)]; !dyn.empty()) {
    EXPECT_LE(dyn.back(), 0.6);
  }
  std::sort(walk_ratios.begin(), walk_ratios.end());
  if (!walk_ratios.empty()) {
    std::printf(
        "  %-16s %.3f  %.3f  (random-walk drift: naming and ratio reported, not asserted)\n",
        "drift (walk)", walk_ratios[walk_ratios.size() / 2], walk_ratios.back());
  }
  std::printf("slowest diagnosis: %.2f s for %zu samples\n", slowest, slowest_samples);
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(bad_ratio, 0);
  EXPECT_EQ(rate_as_delay, 0);
  EXPECT_EQ(delay_as_rate, 0);
}

// Many draws of the cases a delay and a rate law are hardest to tell apart in: a delay, a rate law
// (widening thresholds, a switching front) and a widening law beside a delay, 60 each at 100,
// 200, 500 and 1000 Hz (at 100-200 Hz every delay is 1 sample). Prints per kind and rate how
// often each was named; asserts that a rate law alone is never called delay, and that a delay
// alone is named in 95 % of its draws.
TEST(DiagnosisHiddenEffect, RateOrDelayDraws) {
  if (!long_tests()) GTEST_SKIP() << "set HYSTBENCH_LONG_TESTS=1 for the 960 draws";
  const double rates[] = {100.0, 200.0, 500.0, 1000.0};
  const std::uint64_t first = 5000, draws = 60;
  enum Kind { kDelayAlone, kWideningLaw, kSwitchingFront, kLawAndDelay };
  const char* labels[] = {"delay", "widening law", "switching front", "widening law + delay"};
  int rate_called_delay = 0, delays_named = 0, delay_cases = 0;
  std::printf("%-22s %6s %8s %8s %8s\n", "hidden", "Hz", "delay", "rate", "both");
  for (const Kind kind : {kDelayAlone, kWideningLaw, kSwitchingFront, kLawAndDelay}) {
    for (const double fs : rates) {
      int delay = 0, rate = 0, both = 0;
      for (std::uint64_t seed = first; seed < first + draws; ++seed) {
        HiddenCase c{kind == kDelayAlone ? hc::Cause::kDelay : hc::Cause::kRateDependence, fs,
                     seed};
        c.widening_thresholds = kind != kSwitchingFront && kind != kDelayAlone;
        if (kind == kLawAndDelay) c.also = hc::Cause::kDelay;
        const Outcome o = diagnose_case(make_hidden(c));
        const std::vector<hc::Cause> named = named_causes(o.diagnosis);
        const bool d = names(named, hc::Cause::kDelay),
                   r = names(named, hc::Cause::kRateDependence);
        delay += d ? 1 : 0, rate += r ? 1 : 0, both += d && r ? 1 : 0;
      }
      std::printf("%-22s %6.0f %8d %8d %8d  of %llu\n", labels[kind], fs, delay, rate, both,
                  static_cast<unsigned long long>(draws));
      std::fflush(stdout);
      if (kind == kWideningLaw || kind == kSwitchingFront) rate_called_delay += delay;
      if (kind == kDelayAlone) delays_named += delay, delay_cases += static_cast<int>(draws);
    }
  }
  EXPECT_EQ(rate_called_delay, 0);
  EXPECT_GE(delays_named, 0.95 * delay_cases);
}
