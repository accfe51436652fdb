#include "hystbench/sim/signal_generator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <string>
#include <vector>

namespace hs = hystbench::sim;
using std::numbers::pi;

namespace {

hs::SignalSpec periodic(hs::SignalKind kind, double amplitude, double offset, double f) {
  hs::SignalSpec s;
  s.kind = kind;
  s.amplitude = amplitude;
  s.offset = offset;
  s.frequency_hz = f;
  return s;
}

std::pair<double, double> bounds(const hs::SignalGenerator& g, double t0, double t1, int n) {
  double lo = INFINITY, hi = -INFINITY;
  for (int k = 0; k <= n; ++k) {
    const double v = g.value(t0 + (t1 - t0) * k / n);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  return {lo, hi};
}

/// |DFT| of the samples at frequency f, normalised to the amplitude of a sine at f.
double amplitude_at(const std::vector<double>& x, double dt, double f) {
  std::complex<double> sum = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sum += x[k] * std::exp(std::complex<double>(0.0, -2.0 * pi * f * k * dt));
  }
  return 2.0 * std::abs(sum) / x.size();
}

/// Times of the rising zero crossings of g - offset in [t0, t1).
std::vector<double> rising_crossings(const hs::SignalGenerator& g, double offset, double t0,
                                     double t1, double dt) {
  std::vector<double> t;
  for (double a = t0; a + dt < t1; a += dt) {
    const double va = g.value(a) - offset, vb = g.value(a + dt) - offset;
    if (va < 0.0 && vb >= 0.0) t.push_back(a + dt * va / (va - vb));
  }
  return t;
}

std::string error_of(const hs::SignalSpec& spec) {
  try {
    hs::make_signal_generator(spec);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no exception";
}

}  // namespace

TEST(SignalKind, NamesRoundTripAndUnknownNamesListTheValidOnes) {
  for (const char* name : {"sine", "decaying_sine", "triangle", "sawtooth", "steps",
                           "multi_frequency", "chirp", "csv"}) {
    EXPECT_EQ(hs::to_string(hs::signal_kind_from_string(name)), name);
  }
  try {
    hs::signal_kind_from_string("square");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("square"), std::string::npos);
    for (const char* name : {"sine", "decaying_sine", "multi_frequency", "chirp", "csv"}) {
      EXPECT_NE(m.find(name), std::string::npos) << m;
    }
  }
}

TEST(SineSignal, HasThePeriodAmplitudeAndPhase) {
  const auto g = hs::make_signal_generator(periodic(hs::SignalKind::kSine, 2.0, 5.0, 4.0));
  EXPECT_TRUE(std::isinf(g->duration_s()));
  EXPECT_NEAR(g->value(0.0), 5.0, 1e-12);
  EXPECT_GT(g->value(0.01), 5.0);  // rising at phase 0
  for (double t : {0.013, 0.4, 1.77}) EXPECT_NEAR(g->value(t + 0.25), g->value(t), 1e-9);
  const auto [lo, hi] = bounds(*g, 0.0, 0.25, 10000);
  EXPECT_NEAR(lo, 3.0, 1e-6);
  EXPECT_NEAR(hi, 7.0, 1e-6);
}

TEST(TriangleSignal, RampsAtConstantRateBetweenTheBounds) {
  const double a = 3.0, f = 2.0;
  const auto g = hs::make_signal_generator(periodic(hs::SignalKind::kTriangle, a, 1.0, f));
  EXPECT_NEAR(g->value(0.0), 1.0, 1e-12);
  EXPECT_NEAR(g->value(0.125), 1.0 + a, 1e-12);  // peak at a quarter period
  EXPECT_NEAR(g->value(0.375), 1.0 - a, 1e-12);
  const double dt = 1e-4;
  for (double t = 0.0; t < 1.0; t += 0.0123) {
    const double slope = (g->value(t + dt) - g->value(t)) / dt;
    const bool near_turn = std::abs(std::remainder(t - 0.125, 0.25)) < 2 * dt;
    if (!near_turn) {
      EXPECT_NEAR(std::abs(slope), 4.0 * a * f, 1e-6) << "t=" << t;
    }
  }
  const auto [lo, hi] = bounds(*g, 0.0, 1.0, 8000);
  EXPECT_NEAR(lo, 1.0 - a, 1e-9);
  EXPECT_NEAR(hi, 1.0 + a, 1e-9);
}

TEST(SawtoothSignal, RisesAtConstantRateAndFallsSharply) {
  const double a = 1.0, f = 5.0;
  const auto g = hs::make_signal_generator(periodic(hs::SignalKind::kSawtooth, a, 0.0, f));
  EXPECT_NEAR(g->value(0.0), 0.0, 1e-12);
  EXPECT_NEAR((g->value(0.05) - g->value(0.0)) / 0.05, 2.0 * a * f, 1e-9);
  EXPECT_GT(g->value(0.0999), 0.99);  // just before the fall at half a period
  EXPECT_LT(g->value(0.1001), -0.99);
  for (double t : {0.01, 0.33}) EXPECT_NEAR(g->value(t + 0.2), g->value(t), 1e-9);
}

TEST(DecayingSineSignal, ReproducesTheMultilayerPaperEquation12) {
  // u(t) = 15 (-0.25 t + 10.6165) |sin(0.2 pi t)|: amplitude 15 * 10.6165 decaying linearly to
  // 0 at t = 10.6165 / 0.25, |sin| of a 0.1 Hz sine.
  hs::SignalSpec s;
  s.kind = hs::SignalKind::kDecayingSine;
  s.amplitude = 15.0 * 10.6165;
  s.frequency_hz = 0.1;
  s.duration_s = 10.6165 / 0.25;
  s.rectified = true;
  const auto g = hs::make_signal_generator(s);
  EXPECT_DOUBLE_EQ(g->duration_s(), s.duration_s);
  for (double t = 0.0; t < s.duration_s; t += 0.37) {
    EXPECT_NEAR(g->value(t), 15.0 * (-0.25 * t + 10.6165) * std::abs(std::sin(0.2 * pi * t)), 1e-9);
  }
  EXPECT_EQ(g->value(s.duration_s + 1.0), 0.0);
  // Successive loop peaks (every 5 s) decrease.
  double previous = INFINITY;
  for (double t = 2.5; t < s.duration_s; t += 5.0) {
    EXPECT_LT(g->value(t), previous);
    previous = g->value(t);
  }
}

TEST(DecayingSineSignal, UnrectifiedSwingsBothWaysAndNeedsAFiniteDuration) {
  hs::SignalSpec s = periodic(hs::SignalKind::kDecayingSine, 1.0, 0.0, 1.0);
  s.duration_s = 4.0;
  const auto g = hs::make_signal_generator(s);
  EXPECT_NEAR(g->value(0.25), 1.0 - 0.25 / 4.0, 1e-12);
  EXPECT_NEAR(g->value(0.75), -(1.0 - 0.75 / 4.0), 1e-12);
  s.duration_s = hs::kInfiniteDuration;
  EXPECT_NE(error_of(s).find("duration_s"), std::string::npos);
}

TEST(StepsSignal, HoldsEachLevelForItsTime) {
  hs::SignalSpec s;
  s.kind = hs::SignalKind::kSteps;
  s.offset = 10.0;
  s.steps = {{1.0, 0.5}, {-2.0, 1.0}, {4.0, 0.25}};
  const auto g = hs::make_signal_generator(s);
  EXPECT_DOUBLE_EQ(g->duration_s(), 1.75);
  EXPECT_EQ(g->value(0.0), 11.0);
  EXPECT_EQ(g->value(0.49), 11.0);
  EXPECT_EQ(g->value(0.5), 8.0);
  EXPECT_EQ(g->value(1.49), 8.0);
  EXPECT_EQ(g->value(1.6), 14.0);
  EXPECT_EQ(g->value(100.0), 14.0);  // the last level holds

  s.repeat_steps = true;
  const auto r = hs::make_signal_generator(s);
  EXPECT_TRUE(std::isinf(r->duration_s()));
  EXPECT_EQ(r->value(1.75 + 0.2), 11.0);
  EXPECT_EQ(r->value(3 * 1.75 + 0.7), 8.0);

  s.steps[1].hold_s = 0.0;
  EXPECT_NE(error_of(s).find("steps[1].hold_s"), std::string::npos);
}

TEST(MultiFrequencySignal, ContainsTheRateDependentPaperFrequenciesAndStaysInBounds) {
  hs::SignalSpec s;
  s.kind = hs::SignalKind::kMultiFrequency;
  s.amplitude = 6.25;
  s.offset = 20.0;
  const auto g = hs::make_signal_generator(s);
  const double dt = 1e-3;
  const auto x = hs::sample_signal(*g, dt, 8.0);  // two modulation periods
  for (const double v : x) {
    ASSERT_LE(std::abs(v - 20.0), 6.25);
  }
  std::vector<double> centred(x);
  for (auto& v : centred) v -= 20.0;
  for (const double f : {1.0, 10.0, 19.0}) {
    EXPECT_GT(amplitude_at(centred, dt, f), 0.1 * 6.25) << f << " Hz";
  }
  for (const double f : {5.0, 14.0, 30.0}) {
    EXPECT_LT(amplitude_at(centred, dt, f), 0.01 * 6.25) << f << " Hz";
  }
  // The amplitudes vary in time: the 10 Hz content differs between two 1-s windows.
  const std::vector<double> first(centred.begin(), centred.begin() + 1000);
  const std::vector<double> third(centred.begin() + 2000, centred.begin() + 3000);
  EXPECT_GT(std::abs(amplitude_at(first, dt, 10.0) - amplitude_at(third, dt, 10.0)), 0.1);
}

TEST(ChirpSignal, SweepsLinearlyFromStartToEndFrequency) {
  hs::SignalSpec s = periodic(hs::SignalKind::kChirp, 1.0, 0.0, 2.0);
  s.end_frequency_hz = 20.0;
  s.duration_s = 10.0;
  const auto g = hs::make_signal_generator(s);
  const auto t = rising_crossings(*g, 0.0, 0.0, 12.0, 1e-4);
  ASSERT_GT(t.size(), 10u);
  // Instantaneous frequency from each period: f(t) = 2 + 18 t / 10, and 20 Hz after the sweep.
  for (std::size_t k = 1; k < t.size(); ++k) {
    const double mid = 0.5 * (t[k] + t[k - 1]);
    const double expected = mid < 10.0 ? 2.0 + 1.8 * mid : 20.0;
    if (std::abs(mid - 10.0) > 0.1) {
      EXPECT_NEAR(1.0 / (t[k] - t[k - 1]), expected, 0.05 * expected) << "t=" << mid;
    }
  }
  s.duration_s = hs::kInfiniteDuration;
  EXPECT_NE(error_of(s).find("duration_s"), std::string::npos);
}

TEST(SamplesSignal, InterpolatesLinearlyAndHoldsTheEnds) {
  hs::SignalSpec s;
  s.kind = hs::SignalKind::kSamples;
  s.samples = {{0.0, 1.0}, {1.0, 3.0}, {3.0, -1.0}};
  const auto g = hs::make_signal_generator(s);
  EXPECT_DOUBLE_EQ(g->duration_s(), 3.0);
  EXPECT_DOUBLE_EQ(g->value(0.5), 2.0);
  EXPECT_DOUBLE_EQ(g->value(2.0), 1.0);
  EXPECT_DOUBLE_EQ(g->value(1.0), 3.0);
  EXPECT_DOUBLE_EQ(g->value(-1.0), 1.0);
  EXPECT_DOUBLE_EQ(g->value(9.0), -1.0);

  s.samples[2].t_s = 1.0;
  EXPECT_NE(error_of(s).find("samples[2].t_s"), std::string::npos);
  s.samples.clear();
  EXPECT_NE(error_of(s).find("samples"), std::string::npos);
}

TEST(UniformSignal, InterpolatesOnTheGridAndHoldsTheEnds) {
  const auto g = hs::make_uniform_signal({1.0, 3.0, -1.0}, 0.5);
  EXPECT_DOUBLE_EQ(g->duration_s(), 1.0);
  EXPECT_DOUBLE_EQ(g->value(0.0), 1.0);
  EXPECT_DOUBLE_EQ(g->value(0.25), 2.0);
  EXPECT_DOUBLE_EQ(g->value(0.5), 3.0);
  EXPECT_DOUBLE_EQ(g->value(0.75), 1.0);
  EXPECT_DOUBLE_EQ(g->value(-1.0), 1.0);
  EXPECT_DOUBLE_EQ(g->value(7.0), -1.0);
  EXPECT_DOUBLE_EQ(g->value(NAN), 1.0);
  EXPECT_THROW(hs::make_uniform_signal({}, 0.1), std::invalid_argument);
  EXPECT_THROW(hs::make_uniform_signal({1.0}, 0.0), std::invalid_argument);
  try {
    (void)hs::make_uniform_signal({1.0, NAN}, 0.1);
    ADD_FAILURE() << "a NaN value was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("values[1]"), std::string::npos) << e.what();
  }
}

TEST(SignalSpec, InvalidFieldsAreNamed) {
  auto s = periodic(hs::SignalKind::kSine, 1.0, 0.0, 0.0);
  EXPECT_NE(error_of(s).find("frequency_hz"), std::string::npos);
  s = periodic(hs::SignalKind::kTriangle, NAN, 0.0, 1.0);
  EXPECT_NE(error_of(s).find("amplitude"), std::string::npos);
  s.kind = hs::SignalKind::kMultiFrequency;
  s.amplitude = 1.0;
  s.component_frequencies_hz = {1.0, -10.0};
  EXPECT_NE(error_of(s).find("component_frequencies_hz[1]"), std::string::npos);
}

TEST(SampleSignal, LeavesOutTheEndPointSoSignalsConcatenate) {
  const auto g = hs::make_signal_generator(periodic(hs::SignalKind::kSine, 1.0, 0.0, 1.0));
  const auto x = hs::sample_signal(*g, 0.01, 2.0);
  ASSERT_EQ(x.size(), 200u);
  EXPECT_NEAR(x[25], 1.0, 1e-12);                                    // t = 0.25 s, the first peak
  EXPECT_THROW(hs::sample_signal(*g, 0.01), std::invalid_argument);  // infinite duration
  EXPECT_THROW(hs::sample_signal(*g, 0.0, 1.0), std::invalid_argument);
}
