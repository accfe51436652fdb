#include "hystbench/daemon/loop/oscillation_detector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace hd = hystbench::daemon;

namespace {

constexpr double kRate = 10000.0, kSpan = 36.0;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

hd::OscillationDetector detector(double f0 = 1850.0) {
  return hd::OscillationDetector({kRate, f0, kSpan, 0.005});
}

// Feeds error(k) for `seconds`; the tick it tripped at, or -1.
template <typename Error>
long first_trip(hd::OscillationDetector& d, double seconds, Error error) {
  const auto n = static_cast<long>(seconds * kRate);
  for (long k = 0; k < n; ++k) {
    if (d.update(error(k), static_cast<std::uint64_t>(k))) return k;
  }
  return -1;
}

}  // namespace

// A stable loop's error: the sensor's noise and a fast reference's harmonics at 1 % of the span
// (a 500 Hz sine's third and fourth right in the band), and the start from rest ringing down.
TEST(OscillationDetector, LeavesAStableLoopsErrorAlone) {
  hd::OscillationDetector d = detector();
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.005);
  const long trip = first_trip(d, 2.0, [&](long k) {
    const double t = static_cast<double>(k) / kRate;
    const double ring = 0.5 * kSpan * std::exp(-t / 0.002) * std::sin(kTwoPi * 2900.0 * t);
    return noise(rng) +
           0.01 * kSpan * (std::sin(kTwoPi * 1500.0 * t) + std::sin(kTwoPi * 2000.0 * t)) + ring;
  });
  EXPECT_EQ(trip, -1);
  EXPECT_FALSE(d.trip().tripped);
}

// An unstable loop: an oscillation near the band's centre growing from the noise, e-fold every
// 5 ms. It trips long before the oscillation reaches a tenth of the span.
TEST(OscillationDetector, TripsOnAGrowingOscillation) {
  hd::OscillationDetector d = detector();
  double amplitude_at_trip = 0.0;
  const long trip = first_trip(d, 1.0, [&](long k) {
    const double t = static_cast<double>(k) / kRate;
    amplitude_at_trip = 0.001 * std::exp(t / 0.005);
    return amplitude_at_trip * std::sin(kTwoPi * 1900.0 * t);
  });
  ASSERT_GT(trip, 0);
  EXPECT_TRUE(d.trip().growing);
  EXPECT_LT(amplitude_at_trip, 0.1 * kSpan);
  EXPECT_EQ(d.trip().tick, static_cast<std::uint64_t>(trip));
  EXPECT_TRUE(d.update(0.0, trip + 1));  // stays tripped
}

// A limit cycle (the growth stopped by a clamp): a steady oscillation of a tenth of the span
// trips within 20 ms and a few windows.
TEST(OscillationDetector, TripsOnASustainedOscillation) {
  hd::OscillationDetector d = detector();
  const long trip = first_trip(d, 1.0, [&](long k) {
    return 0.1 * kSpan * std::sin(kTwoPi * 1850.0 * static_cast<double>(k) / kRate);
  });
  ASSERT_GT(trip, 0);
  EXPECT_LT(trip, static_cast<long>(0.03 * kRate));
  EXPECT_GE(trip, static_cast<long>(0.02 * kRate) - 1);
  EXPECT_FALSE(d.trip().growing && d.trip().rms_um < 0.05 * kSpan);
}

TEST(OscillationDetector, ClampsOptionsOutOfRangeInsteadOfThrowing) {
  hd::OscillationDetector d({kRate, 1e9, -1.0, NAN, -5.0});
  EXPECT_LT(d.options().frequency_hz, kRate / 2.0);
  EXPECT_GT(d.options().span_um, 0.0);
  EXPECT_FALSE(d.update(NAN, 0));
  EXPECT_EQ(d.options().period_samples, 0.0);  // not periodic
}

// A stable loop tracking a fast reference near the peak of |S|: its answer, a 500 Hz error of
// 14 % of the span with its harmonics, repeats every period of the reference. Watched as it is,
// it looks sustained and trips; watched as its change over the reference's period, it is left
// alone, while an oscillation of the loop's own (1850 Hz, not locked to the reference) beside
// it still trips, growing or sustained.
TEST(OscillationDetector, LeavesAnErrorLockedToAPeriodicReferenceAlone) {
  const auto locked = [](long k) {
    const double t = static_cast<double>(k) / kRate;
    return 0.14 * kSpan * std::sin(kTwoPi * 500.0 * t) +
           0.05 * kSpan * std::sin(kTwoPi * 1000.0 * t + 0.3) +
           0.03 * kSpan * std::sin(kTwoPi * 1500.0 * t + 1.1);
  };
  hd::OscillationDetector plain = detector(1130.0);
  EXPECT_GT(first_trip(plain, 0.5, locked), 0);
  hd::OscillationDetector periodic({kRate, 1130.0, kSpan, 0.005, kRate / 500.0});
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.005);
  EXPECT_EQ(first_trip(periodic, 2.0, [&](long k) { return locked(k) + noise(rng); }), -1);

  hd::OscillationDetector growing({kRate, 1130.0, kSpan, 0.005, kRate / 500.0});
  double amplitude_at_trip = 0.0;
  const long grown = first_trip(growing, 1.0, [&](long k) {
    const double t = static_cast<double>(k) / kRate;
    amplitude_at_trip = 0.001 * std::exp(t / 0.01);
    return locked(k) + amplitude_at_trip * std::sin(kTwoPi * 1170.0 * t);
  });
  ASSERT_GT(grown, 0);
  EXPECT_TRUE(growing.trip().growing);
  EXPECT_LT(amplitude_at_trip, 0.1 * kSpan);

  // A period of fractional ticks (10 kHz / 30 Hz): the change is read between two ticks.
  hd::OscillationDetector sustained({kRate, 1130.0, kSpan, 0.005, kRate / 30.0});
  const long cycle = first_trip(sustained, 1.0, [&](long k) {
    const double t = static_cast<double>(k) / kRate;
    return 0.3 * kSpan * std::sin(kTwoPi * 30.0 * t) + 0.1 * kSpan * std::sin(kTwoPi * 1130.0 * t);
  });
  EXPECT_GT(cycle, 0);
  EXPECT_FALSE(sustained.trip().growing);
}
