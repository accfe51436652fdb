#pragma once
// Shared helpers of the diagnosis tests: the hidden-effect cases. Each case builds a simulated
// actuator (sim::SimulatedActuator) whose truth is a point-symmetric Preisach hysteresis (no model
// family contains it, so nothing is found only because the base is a PI) plus exactly one hidden
// effect (or none; two in the several-causes tests), with randomised parameters, seeds, sample
// rates and noise; drives it with the identification excitation; and checks that diagnose() names
// the effect from the data alone (it sees t, u, y and nothing of the configuration) and that the
// extended model's error on a second, independent record of the same actuator (scored as
// validate_model scores a record never fitted) is at most 0.8x the baseline's (0.9x for creep, 1x
// for a drift: see max_ratio). A classical PI baseline misses the Preisach base's bent loop: with
// nothing hidden the diagnosis names that shape (asymmetry, "bent or asymmetric") or nothing; a
// hidden effect is named on top of the shape. The shape's error stays in part in both models on the
// second record, which bounds the ratio. The sweep (hidden_effect_sweep_test.cpp: 72 cases: 8 per
// cause and none at 100 Hz .. 20 kHz, all asserted, and 8 random-walk drifts, reported in their
// own row; confusion table and per-cause ratios printed) runs with HYSTBENCH_LONG_TESTS=1
// (HYSTBENCH_SWEEP_SEED draws other cases, HYSTBENCH_SWEEP_CAUSE=<cause> runs the cases that hide
// it, HYSTBENCH_SWEEP_VERBOSE=1 prints every case's report, not only a wrong one's); by default one
// case per cause runs, at several sample rates.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "hystbench/compensation/diagnosis.hpp"
#include "hystbench/sim/identification_excitation.hpp"
#include "hystbench/sim/preisach_hysteresis.hpp"
#include "hystbench/sim/simulated_actuator.hpp"
#include "hystbench/sim/thermal_drift.hpp"

namespace hystbench::test::diagnosis {

namespace hc = hystbench::compensation;
namespace hs = hystbench::sim;

inline constexpr double kMaxRatio = 0.8;  // extended / baseline rms on the second record

// The bound on the second record's ratio for a named cause. A drift is fitted and removed, not
// carried into the extended model (a drift does not repeat), so on another record the extended
// model gains only what the drift-free refit gains, little where the drift was small: it must
// not be worse.
// A logarithmic creep has lags far longer than a record, whose part the first record shows
// predicts the second only in part: 0.9 (docs/measurements.md, Diagnosis: the creep row of the
// second-record ratios).
inline double max_ratio(hc::Cause named) {
  if (named == hc::Cause::kDrift) return 1.0;
  return named == hc::Cause::kCreep ? 0.9 : kMaxRatio;
}

inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

struct Record {
  std::vector<double> t, u, y;
};

// The excitation of the first record, and a different one (other rates, order of reversals and
// hold levels, loop frequencies) for the second, independent record.
inline hs::IdentificationExcitationOptions excitation_options(double fs, bool second,
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

inline Record run(hs::SimulatedActuator& actuator, const hs::Excitation& x) {
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
inline void scale_to_40um(hs::SimulatedActuatorConfig::Hysteresis& h) {
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
inline hs::SimulatedActuatorConfig::Hysteresis random_preisach(std::mt19937_64& rng) {
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
inline HiddenCase with_widening_law(hc::Cause cause, double fs, std::uint64_t seed,
                                    hc::Cause also) {
  HiddenCase c{cause, fs, seed};
  c.also = also;
  c.widening_thresholds = true;
  return c;
}

inline std::string name_of(const HiddenCase& c) {
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
inline std::string hide_rate_dependence(const HiddenCase& hc_case, hs::SimulatedActuatorConfig& c,
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
inline std::string hide_drift(const HiddenCase& hc_case, hs::SimulatedActuatorConfig& c,
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
inline std::string hide(hc::Cause cause, const HiddenCase& hc_case, hs::SimulatedActuatorConfig& c,
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

inline HiddenData make_hidden(const HiddenCase& hc_case) {
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
inline double rms_error(hc::ActuatorModel model, const Record& r) {
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

inline Outcome diagnose_case(const HiddenData& d) {
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

inline std::string summary(const Outcome& o) {
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

inline void expect_named(const HiddenCase& c) {
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

inline bool long_tests() {
  const char* v = std::getenv("HYSTBENCH_LONG_TESTS");
  return v != nullptr && std::string(v) == "1";
}

inline std::vector<hc::Cause> named_causes(const hc::Diagnosis& d) {
  std::vector<hc::Cause> v;
  for (const hc::NamedCause& n : d.causes) v.push_back(n.cause);
  return v;
}

inline bool names(const std::vector<hc::Cause>& named, hc::Cause cause) {
  return std::find(named.begin(), named.end(), cause) != named.end();
}

}  // namespace hystbench::test::diagnosis
