#include "hystbench/compensation/measured_response.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <span>
#include <stdexcept>

#include "hystbench/compensation/shaping_filter.hpp"
#include "hystbench/sim/frequency_response_excitation.hpp"

namespace hc = hystbench::compensation;
namespace hs = hystbench::sim;

namespace {

struct Measured {
  hs::FrequencyResponseExcitation x;
  std::vector<double> y;
};

// The default excitation at 10 kHz through a resonant low-pass (a known discrete plant) times
// `gain`, plus white noise of `noise_um` and a drift of `drift` per sample.
Measured through_plant(double gain, double noise_um, double drift) {
  hs::FrequencyResponseExcitationOptions o;
  o.rate_hz = 10000.0;
  Measured m{hs::make_frequency_response_excitation(o), {}};
  hc::ShapingFilter plant({{}, {2000.0, 0.1}}, 1e-4);
  plant.reset(m.x.u.front());
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, noise_um);
  for (std::size_t k = 0; k < m.x.u.size(); ++k) {
    m.y.push_back(gain * plant.step(m.x.u[k]) + (noise_um > 0.0 ? n(rng) : 0.0) + drift * k);
  }
  return m;
}

hc::MeasuredResponse estimate(const Measured& m, std::size_t segment) {
  const hs::ResponseMeasurementSegment& s = m.x.segments[segment];
  const std::size_t n = m.x.period * s.periods;
  return hc::estimate_response(std::span(m.x.u).subspan(s.first, n),
                               std::span(m.y).subspan(s.first, n), m.x.period, m.x.lines, 10000.0);
}

}  // namespace

TEST(MeasuredResponse, RecoversAKnownPlantExactlyWithoutNoise) {
  const Measured m = through_plant(0.3, 0.0, 0.0);
  const hc::ShapingFilter plant({{}, {2000.0, 0.1}}, 1e-4);
  for (std::size_t s = 0; s < m.x.segments.size(); ++s) {
    const hc::MeasuredResponse r = estimate(m, s);
    ASSERT_EQ(r.size(), m.x.lines.size());
    for (std::size_t i = 0; i < r.size(); ++i) {
      const std::complex<double> truth = 0.3 * plant.response(r.frequency_hz[i]);
      ASSERT_NEAR(std::abs(r.response[i] - truth), 0.0, 1e-9 * std::abs(truth))
          << r.frequency_hz[i];
      ASSERT_LT(r.noise[i], 1e-9);
      ASSERT_GT(r.coherence[i], 0.999999);
    }
    EXPECT_LT(r.output_noise_rms, 1e-9);
  }
}

// The noise of each line is the spread of its mean; the true error stays within a few of it,
// and the output's non-repeating part is the noise added.
TEST(MeasuredResponse, ItsNoiseIsTheSpreadOfTheMeanAndItsOutputNoiseTheNoiseAdded) {
  const Measured m = through_plant(0.3, 0.005, 0.0);
  const hc::ShapingFilter plant({{}, {2000.0, 0.1}}, 1e-4);
  const hc::MeasuredResponse r = estimate(m, 1);
  int within = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    const std::complex<double> truth = 0.3 * plant.response(r.frequency_hz[i]);
    within += std::abs(r.response[i] - truth) <= 3.0 * r.noise[i];
    EXPECT_GT(r.noise[i], 0.0);
  }
  EXPECT_GE(within, static_cast<int>(0.9 * r.size()));
  EXPECT_NEAR(r.output_noise_rms, 0.005, 0.0005);
}

TEST(MeasuredResponse, ADriftOfTheOutputDoesNotLeakIntoTheLines) {
  const hc::MeasuredResponse clean = estimate(through_plant(0.3, 0.0, 0.0), 0);
  const hc::MeasuredResponse drifting = estimate(through_plant(0.3, 0.0, 2e-5), 0);
  for (std::size_t i = 0; i < clean.size(); ++i) {
    ASSERT_NEAR(std::abs(drifting.response[i] - clean.response[i]), 0.0,
                1e-9 * std::abs(clean.response[i]));
  }
}

TEST(MeasuredResponse, RefusesWhatIsNotWholePeriodsOrLinesItCannotEstimate) {
  const std::vector<double> u(1000, 1.0), y(1000, 1.0);
  const std::vector<std::size_t> lines = {1, 2};
  EXPECT_THROW(hc::estimate_response(u, y, 300, lines, 1e4), std::invalid_argument);
  EXPECT_THROW(hc::estimate_response(u, y, 1000, lines, 1e4), std::invalid_argument);
  const std::vector<std::size_t> beyond = {1, 300};
  EXPECT_THROW(hc::estimate_response(u, y, 500, beyond, 1e4), std::invalid_argument);
  // A constant drive excites no line.
  EXPECT_THROW(hc::estimate_response(u, y, 500, lines, 1e4), std::invalid_argument);
}
