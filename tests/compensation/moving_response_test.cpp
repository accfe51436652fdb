#include "hystbench/compensation/moving_response.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/compensation/shaping_filter.hpp"
#include "hystbench/sim/frequency_response_excitation.hpp"

namespace hc = hystbench::compensation;
namespace hs = hystbench::sim;

namespace {

constexpr double kRate = 1000.0, kDt = 1.0 / kRate;
constexpr double kGain = 0.3;  // [um/V]

// frf's drive at 1 kHz over 0-150 V.
hs::FrequencyResponseExcitation frf_drive() {
  hs::FrequencyResponseExcitationOptions o;
  o.rate_hz = kRate;
  return hs::make_frequency_response_excitation(o);
}

// A one-play rate-dependent PI whose weight grows with |du/dt| by `c` per V/s (its output
// (kGain + c |du/dt|) u), behind a 190 Hz mode (zeta 0.07), with white noise of noise_um.
std::vector<double> through_rate_law(const std::vector<double>& u, double c, double noise_um) {
  hc::ModifiedPiParameters base{{{0.0}, {kGain}, 0.0}, {{0.0}, {1.0}}, 0.0};
  hc::RateDependentPiParameters p{base, {c}, 0.0};
  p.rate_law = hc::RateLaw::kMagnitude;
  hc::RateDependentPiModel law(p, kDt);
  law.reset(u.front());
  hc::ShapingFilter mode({{}, {190.0, 0.07}}, kDt);
  mode.reset(kGain * u.front());
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n(0.0, noise_um);
  std::vector<double> y;
  for (const double v : u) y.push_back(mode.step(law.step(v)) + (noise_um > 0.0 ? n(rng) : 0.0));
  return y;
}

hc::MovingResponse measure(const hs::FrequencyResponseExcitation& d, const std::vector<double>& y) {
  return hc::estimate_moving_response(d.u, y, d.moving.ramps, d.moving.tone_hz, kRate);
}

}  // namespace

// The moving part: ramps across the middle half of the span, alternately up and down after one
// that settles, a sine of a fiftieth of the rate on each over whole cycles, never turning the
// motion (the drive's step keeps the ramp's sign), within the slew limit.
TEST(MovingExcitation, RampsAlternateAndTheirSineNeverTurnsTheMotion) {
  const hs::FrequencyResponseExcitation d = frf_drive();
  const hs::MovingExcitation& m = d.moving;
  ASSERT_EQ(m.ramps.size(), 4u);
  EXPECT_NEAR(m.tone_hz, 20.0, 1e-9);
  for (std::size_t i = 0; i < m.ramps.size(); ++i) {
    const hc::MovingRamp& r = m.ramps[i];
    EXPECT_EQ(r.rising, i % 2 == 1) << i;  // the settling ramp rose; then down, up, down, up
    const double cycles = static_cast<double>(r.length) * m.tone_hz / kRate;
    EXPECT_NEAR(cycles, std::round(cycles), 1e-9);
    EXPECT_GE(cycles, 8.0);
    for (std::size_t k = r.first + 1; k < r.first + r.length; ++k) {
      const double step = d.u[k] - d.u[k - 1];
      ASSERT_GT(r.rising ? step : -step, 0.0) << "ramp " << i << " turns at sample " << k;
    }
    EXPECT_NEAR(d.u[r.first], r.rising ? 37.5 : 112.5, 1e-9);
  }
  EXPECT_EQ(m.ramps.back().first + m.ramps.back().length, d.u.size());
  // A slow slew limit lengthens the ramps (more cycles), never outruns the limit.
  hs::FrequencyResponseExcitationOptions o;
  o.rate_hz = kRate;
  o.slew_v_per_s = 100.0;
  const hs::FrequencyResponseExcitation slow = hs::make_frequency_response_excitation(o);
  for (std::size_t k = slow.moving.ramps.front().first; k < slow.u.size(); ++k) {
    ASSERT_LE(std::abs(slow.u[k] - slow.u[k - 1]), 100.0 * kDt * (1.0 + 1e-9)) << k;
  }
  o.moving_tone_fraction = 0.0;
  EXPECT_TRUE(hs::make_frequency_response_excitation(o).moving.ramps.empty());
  o.moving_ramps = 3;
  o.moving_tone_fraction = 0.02;
  EXPECT_THROW(hs::make_frequency_response_excitation(o), std::invalid_argument);
}

// A stage whose weight grows with |du/dt| has a right-half-plane zero on its falling branches at
// kGain / (2 pi c u) Hz (u the drive there) and a left-half-plane one on its rising branches: the
// falling ramps lag the rising ones, and the zero comes out at the ramps' middle drive within
// 10 %, through a 190 Hz mode and the sensor's 5 nm of noise. A weight that falls with the rate
// makes the rising ramps lag.
TEST(MovingResponse, FindsTheZeroARateLawPutsOnOneDirection) {
  const hs::FrequencyResponseExcitation d = frf_drive();
  const double c = kGain / (2.0 * std::numbers::pi * 30.0 * 75.0);  // a 30 Hz zero at 75 V
  const hc::MovingResponse m = measure(d, through_rate_law(d.u, c, 0.005));
  EXPECT_EQ(m.lagging, "falling");
  EXPECT_EQ(m.ramps, 4u);
  EXPECT_NEAR(m.zero_hz, 30.0, 3.0) << m.lag_deg << " deg";
  EXPECT_LT(m.lag_noise_deg, 0.5);
  const hc::MovingResponse back = measure(d, through_rate_law(d.u, -c, 0.005));
  EXPECT_EQ(back.lagging, "rising");
  EXPECT_NEAR(back.zero_hz, 30.0, 3.0) << back.lag_deg << " deg";
}

// Without a rate law the mode and the noise lag neither direction: no zero.
TEST(MovingResponse, ARateIndependentStageHasNoZero) {
  const hs::FrequencyResponseExcitation d = frf_drive();
  const hc::MovingResponse m = measure(d, through_rate_law(d.u, 0.0, 0.005));
  EXPECT_EQ(m.zero_hz, 0.0) << m.lag_deg << " +/- " << m.lag_noise_deg << " deg";
  EXPECT_LT(m.lag_deg, 0.5);
  EXPECT_NEAR(std::abs(m.rising), kGain, 0.02 * kGain);  // the mode adds 1.1 % at 20 Hz
}

TEST(MovingResponse, RefusesWhatItCannotMeasure) {
  const hs::FrequencyResponseExcitation d = frf_drive();
  const std::vector<double> y = through_rate_law(d.u, 0.0, 0.0);
  const std::vector<hc::MovingRamp> rising_only = {d.moving.ramps[1], d.moving.ramps[3]};
  EXPECT_THROW(hc::estimate_moving_response(d.u, y, rising_only, 20.0, kRate),
               std::invalid_argument);
  const std::vector<hc::MovingRamp> short_ramps = {{d.moving.ramps[0].first, 60, false},
                                                   {d.moving.ramps[1].first, 60, true}};
  EXPECT_THROW(hc::estimate_moving_response(d.u, y, short_ramps, 20.0, kRate),
               std::invalid_argument);
  const std::vector<hc::MovingRamp> beyond = {{d.u.size() - 100, 400, false}, d.moving.ramps[1]};
  EXPECT_THROW(hc::estimate_moving_response(d.u, y, beyond, 20.0, kRate), std::invalid_argument);
  EXPECT_THROW(hc::estimate_moving_response(d.u, y, d.moving.ramps, 600.0, kRate),
               std::invalid_argument);
}
