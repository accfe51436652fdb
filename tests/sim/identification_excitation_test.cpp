#include "hystbench/sim/identification_excitation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace hs = hystbench::sim;

namespace {

constexpr double kMin = 0.0, kMax = 150.0, kDt = 1e-3;

std::vector<double> slice(const hs::Excitation& e, const hs::ExcitationSegment& s) {
  return {e.samples.begin() + s.begin, e.samples.begin() + s.end};
}

const hs::ExcitationSegment& segment(const hs::Excitation& e, const std::string& name) {
  const auto* s = e.find(name);
  if (s == nullptr) throw std::runtime_error("no segment " + name);
  return *s;
}

/// Values of the strict local maxima.
std::vector<double> peaks(const std::vector<double>& x) {
  std::vector<double> p;
  for (std::size_t k = 1; k + 1 < x.size(); ++k) {
    if (x[k] > x[k - 1] && x[k] >= x[k + 1]) p.push_back(x[k]);
  }
  return p;
}

int direction_changes(const std::vector<double>& x) {
  int changes = 0, last = 0;
  for (std::size_t k = 1; k < x.size(); ++k) {
    const int d = (x[k] > x[k - 1]) - (x[k] < x[k - 1]);
    if (d != 0 && last != 0 && d != last) ++changes;
    if (d != 0) last = d;
  }
  return changes;
}

}  // namespace

TEST(IdentificationExcitation, DefaultCoversEverySegmentInTwentyToFortySeconds) {
  const auto e = hs::identification_excitation(kMin, kMax, kDt);
  const double duration = e.samples.size() * e.dt_s;
  EXPECT_GE(duration, 20.0);
  EXPECT_LE(duration, 40.0);
  EXPECT_EQ(e.dt_s, kDt);
  for (const char* name : {"major_loop", "minor_loops", "rate_0.5hz", "rate_2hz", "rate_10hz",
                           "reversals", "hold_1", "hold_2", "hold_3", "hold_4"}) {
    EXPECT_NE(e.find(name), nullptr) << name;
  }
  EXPECT_EQ(e.segments.front().name, "major_loop");  // the major loop comes first
  // Contiguous, in order, covering every sample.
  std::size_t next = 0;
  for (const auto& s : e.segments) {
    EXPECT_EQ(s.begin, next) << s.name;
    EXPECT_GT(s.end, s.begin) << s.name;
    next = s.end;
  }
  EXPECT_EQ(next, e.samples.size());
  for (const double u : e.samples) {
    ASSERT_GE(u, kMin);
    ASSERT_LE(u, kMax);
  }
}

TEST(IdentificationExcitation, MajorLoopSpansTheRangeFromItsBottom) {
  const auto e = hs::identification_excitation(kMin, kMax, kDt);
  const auto major = slice(e, segment(e, "major_loop"));
  EXPECT_NEAR(major.front(), kMin, 1e-9);
  EXPECT_NEAR(*std::max_element(major.begin(), major.end()), kMax, 1e-3);
  EXPECT_EQ(peaks(major).size(), 2u);  // two cycles: the virgin curve, then the periodic loop
}

TEST(IdentificationExcitation, MinorLoopsAreNestedWithDecayingAmplitude) {
  hs::IdentificationExcitationOptions o;
  const auto e = hs::identification_excitation(kMin, kMax, kDt, o);
  const auto minor = slice(e, segment(e, "minor_loops"));
  const auto p = peaks(minor);
  ASSERT_EQ(p.size(), static_cast<std::size_t>(o.minor_loops));
  for (std::size_t k = 1; k < p.size(); ++k) EXPECT_LT(p[k], p[k - 1]);
  EXPECT_GT(p.front(), kMin + 0.8 * (kMax - kMin));
  EXPECT_LT(p.back(), kMin + 0.2 * (kMax - kMin));
  EXPECT_NEAR(*std::min_element(minor.begin(), minor.end()), kMin, 1e-9);
}

TEST(IdentificationExcitation, RateSegmentsRunTheirCyclesAtTheirRates) {
  hs::IdentificationExcitationOptions o;
  const auto e = hs::identification_excitation(kMin, kMax, kDt, o);
  const std::vector<std::string> names = {"rate_0.5hz", "rate_2hz", "rate_10hz"};
  std::vector<double> max_slope;
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto x = slice(e, segment(e, names[k]));
    EXPECT_EQ(peaks(x).size(), static_cast<std::size_t>(o.rate_cycles[k])) << names[k];
    EXPECT_NEAR(x.size() * kDt, o.rate_cycles[k] / o.rate_frequencies_hz[k], 2 * kDt);
    double slope = 0.0;
    for (std::size_t i = 1; i < x.size(); ++i) slope = std::max(slope, std::abs(x[i] - x[i - 1]));
    max_slope.push_back(slope / kDt);
  }
  // Same span at every rate, so the peak slope scales with the frequency.
  EXPECT_NEAR(max_slope[1] / max_slope[0], 4.0, 0.05);
  EXPECT_NEAR(max_slope[2] / max_slope[0], 20.0, 0.5);
}

TEST(IdentificationExcitation, ReversalsAreSharpAtConstantRate) {
  hs::IdentificationExcitationOptions o;
  const auto e = hs::identification_excitation(kMin, kMax, kDt, o);
  const auto x = slice(e, segment(e, "reversals"));
  std::vector<double> path = {0.0};
  path.insert(path.end(), o.reversal_points.begin(), o.reversal_points.end());
  EXPECT_EQ(direction_changes(x), direction_changes(path));
  EXPECT_GE(direction_changes(x), 5);
  const double rate = o.reversal_rate_fraction_per_s * (kMax - kMin);
  int at_rate = 0;
  for (std::size_t k = 1; k < x.size(); ++k) {
    const double slope = std::abs(x[k] - x[k - 1]) / kDt;
    ASSERT_LE(slope, rate * (1.0 + 1e-9));
    at_rate += std::abs(slope - rate) < 1e-6 * rate;
  }
  EXPECT_GT(at_rate, 0.98 * (x.size() - 1));  // all but the samples that straddle a turn
}

TEST(IdentificationExcitation, HoldsAreLongAndFlat) {
  hs::IdentificationExcitationOptions o;
  const auto e = hs::identification_excitation(kMin, kMax, kDt, o);
  for (std::size_t k = 0; k < o.hold_levels.size(); ++k) {
    const auto x = slice(e, segment(e, "hold_" + std::to_string(k + 1)));
    EXPECT_NEAR(x.size() * kDt, o.hold_s, kDt);
    for (const double v : x) ASSERT_EQ(v, kMin + o.hold_levels[k] * (kMax - kMin));
  }
  EXPECT_EQ(e.samples.back(), kMin);
}

TEST(IdentificationExcitation, JoinsWithoutJumpsBeforeTheHolds) {
  const auto e = hs::identification_excitation(kMin, kMax, kDt);
  const std::size_t holds_begin = segment(e, "hold_1").begin;
  // The fastest motion is the 10 Hz segment: 0.8 span * pi * 10 Hz per second.
  const double largest = 0.8 * (kMax - kMin) * M_PI * 10.0 * kDt * 1.01;
  for (std::size_t k = 1; k < holds_begin; ++k) {
    ASSERT_LE(std::abs(e.samples[k] - e.samples[k - 1]), largest) << "k=" << k;
  }
}

TEST(IdentificationExcitation, RejectsBadArgumentsByName) {
  const auto error_of = [](double lo, double hi, double dt, hs::IdentificationExcitationOptions o) {
    try {
      hs::identification_excitation(lo, hi, dt, o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(error_of(kMin, kMax, 0.01, {}).find("dt_s"), std::string::npos);  // 10 Hz: 10 samples
  EXPECT_NE(error_of(kMin, kMax, 0.0, {}).find("dt_s"), std::string::npos);
  EXPECT_NE(error_of(kMax, kMin, kDt, {}).find("range_max"), std::string::npos);
  hs::IdentificationExcitationOptions o;
  o.rate_cycles.pop_back();
  EXPECT_NE(error_of(kMin, kMax, kDt, o).find("rate_cycles"), std::string::npos);
  o = {};
  o.hold_levels = {1.5};
  EXPECT_NE(error_of(kMin, kMax, kDt, o).find("hold_levels[0]"), std::string::npos);
}

TEST(IdentificationExcitation, ScalesToAnyRange) {
  const auto e = hs::identification_excitation(-10.0, 30.0, 5e-4);
  EXPECT_NEAR(*std::min_element(e.samples.begin(), e.samples.end()), -10.0, 1e-9);
  EXPECT_NEAR(*std::max_element(e.samples.begin(), e.samples.end()), 30.0, 1e-9);
  EXPECT_EQ(e.samples.size(), hs::identification_excitation(kMin, kMax, 5e-4).samples.size());
}

// The bench's excitation: a hold at mid-range and a sweep over the whole range before the major
// loops, so every record starts in the same hysteresis state with little creep transient, and
// the reversals last, so the record's end shows the loop's shape rather than creep.
TEST(IdentificationExcitation, SettleSweepAndReversalsLast) {
  hs::IdentificationExcitationOptions o;
  o.precondition_s = 1.5;
  o.settle_s = 0.5;
  o.reversals_last = true;
  const auto e = hs::identification_excitation(kMin, kMax, kDt, o);
  ASSERT_GE(e.segments.size(), 3u);
  EXPECT_EQ(e.segments[0].name, "settle");
  EXPECT_EQ(e.segments[1].name, "precondition");
  EXPECT_EQ(e.segments[2].name, "major_loop");
  EXPECT_EQ(e.segments.back().name, "reversals");
  const auto settle = slice(e, segment(e, "settle"));
  EXPECT_NEAR(settle.size() * kDt, 0.5, 2 * kDt);
  for (const double u : settle) ASSERT_NEAR(u, 0.5 * (kMin + kMax), 1e-9);
  // From the settle level up to range_max and down to range_min, at one rate.
  const auto sweep = slice(e, segment(e, "precondition"));
  EXPECT_NEAR(sweep.size() * kDt, 1.5, 2 * kDt);
  EXPECT_NEAR(sweep.front(), 0.5 * (kMin + kMax), 0.01 * (kMax - kMin));
  EXPECT_NEAR(*std::max_element(sweep.begin(), sweep.end()), kMax, 1e-3);
  EXPECT_NEAR(sweep.back(), kMin, 0.01 * (kMax - kMin));  // the last sample before the end
  EXPECT_EQ(peaks(sweep).size(), 1u);
  double slope = 0.0;
  for (std::size_t k = 1; k < sweep.size(); ++k)
    slope = std::max(slope, std::abs(sweep[k] - sweep[k - 1]));
  EXPECT_NEAR(slope, 1.5 * (kMax - kMin) / 1.5 * kDt, 1e-6 * (kMax - kMin));
  // The holds now come before the reversals, which start where the last hold (range_min) is.
  EXPECT_LT(segment(e, "hold_4").end, segment(e, "reversals").begin + 1);
  EXPECT_NEAR(e.samples.back(), kMin, 0.01 * (kMax - kMin));
  // Same segments as without the options, only more of them.
  const auto plain = hs::identification_excitation(kMin, kMax, kDt);
  EXPECT_EQ(e.segments.size(), plain.segments.size() + 2);
}
