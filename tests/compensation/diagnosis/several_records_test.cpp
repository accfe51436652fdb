// DiagnosisSeveralRecords: records of one device diagnosed together, an effect seen only across
// them named, and a bad set refused naming the record.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "compensation/diagnosis/diagnosis_test_support.hpp"
#include "hystbench/compensation/diagnosis.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/sim/simulated_actuator.hpp"

namespace hystbench::test::diagnosis {

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

}  // namespace hystbench::test::diagnosis
