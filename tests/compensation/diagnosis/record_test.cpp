// Diagnosis: what it reads off the record and says of it: the noise of a repeating input, a record
// with one loop only, a long unscored start, an output another input drives.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "compensation/diagnosis/diagnosis_test_support.hpp"
#include "hystbench/compensation/diagnosis.hpp"
#include "hystbench/sim/simulated_actuator.hpp"

namespace hystbench::test::diagnosis {

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

}  // namespace hystbench::test::diagnosis
