#include "hystbench/compensation/harmonic_resonators.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

namespace hc = hystbench::compensation;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kDt = 1e-4;

// A loop around the resonators alone: e(n) = d(n) - g v(n-1), a periodic disturbance d of
// harmonics at 50 and 150 Hz, the stage a gain g and one tick of delay. Returns e's largest
// magnitude over the ticks [from, to).
struct Loop {
  hc::HarmonicResonators r;
  double g = 1.0;
  double v = 0.0;
  int tick = 0;
  double step() {
    const double t = tick++ * kDt;
    const double d = std::sin(kTwoPi * 50.0 * t) + 0.5 * std::cos(kTwoPi * 150.0 * t + 0.3);
    const double e = d - g * v;
    v = r.step(e);
    return e;
  }
  double largest_error(int from, int to) {
    double m = 0.0;
    while (tick < to) {
      const double e = step();
      if (tick > from) m = std::max(m, std::abs(e));
    }
    return m;
  }
};

// c = 1 / G at each harmonic, G = g z^-1 (what v does to the error).
hc::HarmonicResonatorsSpec inverse_of_stage(double g, double mu) {
  hc::HarmonicResonatorsSpec s;
  for (const double f : {50.0, 150.0}) {
    s.resonators.push_back({f, 1.0 / (g * std::polar(1.0, -kTwoPi * f * kDt)), mu});
  }
  return s;
}

}  // namespace

// With c = 1 / G each harmonic decays by about (1 - mu / 2) a tick: after one time constant
// (2 / mu ticks) more than a fifth of the disturbance is left, after five less than 2 %.
TEST(HarmonicResonators, TakeOutTheHarmonicsTheyAreTunedToAtTheRateTheyState) {
  const double mu = 0.005;
  Loop loop{hc::HarmonicResonators(inverse_of_stage(1.0, mu), kDt)};
  const int tau = static_cast<int>(2.0 / mu);  // two periods of 50 Hz
  const int period = 200;
  EXPECT_GT(loop.largest_error(0, period), 1.0);  // the disturbance as it comes
  EXPECT_GT(loop.largest_error(tau, tau + period), 0.2);
  EXPECT_LT(loop.largest_error(5 * tau, 5 * tau + period), 0.02 * 1.5);
  EXPECT_LT(loop.largest_error(12 * tau, 12 * tau + period), 1e-4);
}

// G's phase known only within 60 degrees and its gain 30 % off: it still converges, slower.
TEST(HarmonicResonators, ConvergeWithTheStagesPhaseAndGainOff) {
  hc::HarmonicResonatorsSpec s = inverse_of_stage(1.0, 0.01);
  for (auto& r : s.resonators) r.gain *= std::polar(1.0, std::numbers::pi / 3.0);
  for (const double g : {0.7, 1.3}) {
    Loop loop{hc::HarmonicResonators(s, kDt), g};
    EXPECT_LT(loop.largest_error(20000, 22000), 1e-3) << "gain x" << g;
  }
}

// The filter is what its response says: R(z) = (mu / 2) [c / (1 - q z^-1) + conj(c) / (1 -
// conj(q) z^-1)], i.e. its impulse answer at tick d >= 0 is mu Re{c q^d}.
TEST(HarmonicResonators, AnswerAnImpulseAsTheirResponseStates) {
  const hc::HarmonicResonatorsSpec s = inverse_of_stage(0.8, 0.02);
  hc::HarmonicResonators r(s, kDt);
  const std::complex<double> zi = std::polar(0.9, 0.4);  // inside the unit circle: converges
  std::complex<double> sum{0.0, 0.0};
  for (int d = 0; d < 2000; ++d) {
    const double h = r.step(d == 0 ? 1.0 : 0.0);
    double expected = 0.0;
    for (const auto& x : s.resonators) {
      expected +=
          x.adaptation * (x.gain * std::polar(1.0, kTwoPi * x.frequency_hz * kDt * d)).real();
    }
    ASSERT_NEAR(h, expected, 1e-12) << d;
    sum += h * std::pow(zi, d);
  }
  EXPECT_NEAR(std::abs(sum - r.response_at(zi)), 0.0, 1e-9);
}

TEST(HarmonicResonators, HoldWhileFrozenStayWithinTheirLimitAndHoldOnNaN) {
  hc::HarmonicResonatorsSpec s;
  s.amplitude_limit = 0.25;
  s.resonators.push_back({100.0, {1.0, 0.0}, 0.05});
  hc::HarmonicResonators r(s, kDt);
  double largest = 0.0;
  for (int k = 0; k < 5000; ++k) largest = std::max(largest, std::abs(r.step(1.0)));
  EXPECT_LE(largest, 0.25 + 1e-12);
  EXPECT_GT(largest, 0.2);  // it grew to the limit
  const double held = r.step(std::nan(""));
  EXPECT_EQ(r.step(std::nan("")), held);
  // Frozen, a constant error adds nothing: the output keeps its amplitude and rotates.
  hc::HarmonicResonators f(s, kDt);
  for (int k = 0; k < 100; ++k) f.step(std::sin(kTwoPi * 100.0 * k * kDt));
  f.set_frozen(true);
  double before = 0.0, after = 0.0;
  for (int k = 100; k < 200; ++k) before = std::max(before, std::abs(f.step(5.0)));
  for (int k = 200; k < 300; ++k) after = std::max(after, std::abs(f.step(5.0)));
  EXPECT_NEAR(after, before, 1e-9);
  f.reset();
  EXPECT_EQ(f.step(0.0), 0.0);
}

TEST(HarmonicResonators, NameTheFieldOfABadSpecAndOutputNothingWithoutResonators) {
  hc::HarmonicResonators none(hc::HarmonicResonatorsSpec{}, kDt);
  EXPECT_EQ(none.step(3.0), 0.0);
  EXPECT_EQ(none.response_at({1.0, 0.0}), std::complex<double>(0.0, 0.0));
  hc::HarmonicResonatorsSpec s = inverse_of_stage(1.0, 0.01);
  s.resonators[1].frequency_hz = 6000.0;  // above Nyquist at 10 kHz
  try {
    hc::HarmonicResonators bad(s, kDt);
    FAIL() << "accepted a resonator above the Nyquist frequency";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("resonators[1].frequency_hz"), std::string::npos)
        << e.what();
  }
  s = inverse_of_stage(1.0, 0.9);
  EXPECT_THROW(hc::HarmonicResonators(s, kDt), std::invalid_argument);
}
