#include "hystbench/compensation/harmonic_resonator_design.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>
#include <vector>

#include "compensation/measured_stage_support.hpp"
#include "hystbench/compensation/loop_design.hpp"

namespace hc = hystbench::compensation;
using hystbench::test::measured;
using hystbench::test::Stage;
using hystbench::test::StageSimulation;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// What a feedforward leaves on a periodic reference: harmonics 1..10 of f_hz, falling slowly
// (as the loopback's hysteresis leaves them), at t [s].
double leftover(double f_hz, double t) {
  double d = 0.0;
  for (int k = 1; k <= 10; ++k) d += std::sin(kTwoPi * k * f_hz * t + 0.7 * k) / std::sqrt(k);
  return d;
}

// The rms of the error over the last `periods` of `ticks` ticks: the stage's output plus the
// leftover, held at 0 by `law` (null: no feedback), the reading answered a tick later.
double error_rms(const Stage& s, const hc::FeedbackLaw* law, double f_hz, int ticks,
                 int periods = 10) {
  StageSimulation sim(s);
  std::optional<hc::FeedbackController> c;
  if (law != nullptr) c.emplace(*law, s.dt);
  const int tail = static_cast<int>(std::lround(periods / (f_hz * s.dt)));
  double y = 0.0, sum = 0.0;
  for (int k = 0; k < ticks; ++k) {
    const double e = -y;  // the reference is 0; y carries the leftover
    const double u = c ? c->step(e) : 0.0;
    y = sim.step(u) + leftover(f_hz, k * s.dt);
    if (!std::isfinite(y) || std::abs(y) > 1e6) return INFINITY;
    if (k >= ticks - tail) sum += y * y;
  }
  return std::sqrt(sum / tail);
}

struct Designed {
  hc::FeedbackLaw loop;
  hc::HarmonicResonatorDesign harmonics;
};

// `o` with the stage's period and f_hz as its fundamental.
Designed design(const Stage& s, double f_hz, hc::HarmonicResonatorOptions o = {}) {
  const std::vector<hc::MeasuredResponse> r = measured(s);
  hc::LoopDesignOptions lo;
  lo.dt_s = s.dt;
  const hc::LoopDesign d = hc::design_loop(r, lo);
  EXPECT_TRUE(d.found) << d.limit;
  o.dt_s = s.dt;
  o.fundamental_hz = f_hz;
  return {d.law, hc::design_harmonic_resonators(r, d.law, hc::measured_modes(r), o)};
}

}  // namespace

// One mode at 800 Hz on a 10 kHz loop: the robust loop's crossover sits near 165 Hz and its |S|
// is above 1 from about 200 to 500 Hz, so a 50 Hz reference's harmonics there come out larger
// with the loop than without it. The resonators take them out: never worse than no feedback,
// and well below the loop alone.
TEST(HarmonicResonatorDesign, MakeTheLoopNeverWorseWhereItAmplifiesTheReferencesHarmonics) {
  const Stage s{1.0, {800.0, 0.06}, 0, 1e-4};
  const double f = 50.0;
  const Designed d = design(s, f);
  ASSERT_FALSE(d.harmonics.spec.empty());
  bool amplified = false;
  for (const hc::HarmonicChoice& h : d.harmonics.harmonics) {
    SCOPED_TRACE(h.frequency_hz);
    amplified = amplified || h.sensitivity > 1.0;
    EXPECT_EQ(h.kept, h.why.empty());
    if (h.sensitivity <= 0.5) {
      EXPECT_FALSE(h.kept);
    }
  }
  EXPECT_TRUE(amplified);
  hc::FeedbackLaw with = d.loop;
  with.harmonics = d.harmonics.spec;
  const int ticks = static_cast<int>(std::lround(40.0 / (f * s.dt)));  // 40 periods
  const double none = error_rms(s, nullptr, f, ticks);
  const double loop = error_rms(s, &d.loop, f, ticks);
  const double both = error_rms(s, &with, f, ticks);
  std::cout << f << " Hz leftover rms: no feedback " << none << ", the loop " << loop << ", with "
            << d.harmonics.spec.resonators.size() << " resonators " << both << " (settling in "
            << d.harmonics.settle_periods << " periods)\n";
  EXPECT_GT(loop, none);  // the premise: the loop alone is worse here
  EXPECT_LT(both, 0.5 * none);
  EXPECT_LT(both, 0.5 * loop);
  // After the design the stage changes as the design allows for: still converged and better.
  for (const double g : {0.7, 1.3}) {
    for (const double m : {0.8, 1.2}) {
      Stage moved = s;
      moved.gain = g;
      moved.mode.natural_frequency_hz *= m;
      EXPECT_LT(error_rms(moved, &with, f, ticks), 0.7 * none) << "gain x" << g << ", mode x" << m;
    }
  }
}

// Where the loop already takes out most of each harmonic (a slow reference far below the
// crossover) nothing is added; a harmonic near a lightly damped mode that may move by 20 % is
// left out (its phase through the stage flips), with the reason.
TEST(HarmonicResonatorDesign, AddNothingBelowTheCrossoverAndLeaveOutHarmonicsNearAMode) {
  const Stage s{1.0, {3000.0, 0.06}, 0, 1e-4};
  const Designed slow = design(s, 2.0);
  EXPECT_TRUE(slow.harmonics.spec.empty());
  ASSERT_EQ(slow.harmonics.harmonics.size(), hc::HarmonicResonatorOptions{}.max_harmonics);
  for (const hc::HarmonicChoice& h : slow.harmonics.harmonics) {
    EXPECT_NE(h.why.find("the loop takes out"), std::string::npos) << h.why;
  }
  const Designed fast = design(s, 300.0);  // harmonics up to 3 kHz: the mode's
  bool near_mode_left_out = false;
  for (const hc::HarmonicChoice& h : fast.harmonics.harmonics) {
    if (h.frequency_hz >= 2400.0 && h.frequency_hz <= 3600.0) {
      EXPECT_FALSE(h.kept) << h.frequency_hz;
      near_mode_left_out = near_mode_left_out || h.why.find("phase") != std::string::npos;
    }
  }
  EXPECT_TRUE(near_mode_left_out);
  EXPECT_FALSE(fast.harmonics.spec.empty());
  hc::FeedbackLaw with = fast.loop;
  with.harmonics = fast.harmonics.spec;
  const int ticks = static_cast<int>(std::lround(60.0 / (300.0 * s.dt)));
  EXPECT_LT(error_rms(s, &with, 300.0, ticks), error_rms(s, &fast.loop, 300.0, ticks));
}

// One mode at 800 Hz, a 100 Hz reference, the loop between the harmonics held tighter than by
// default: together its harmonics would move the loop there by more than that however slowly
// they settle. The highest go, the lower ones (most of a periodic error) stay, and they still
// take out more than the loop alone.
TEST(HarmonicResonatorDesign, LeaveOutTheHighestHarmonicsUntilTheRestSettle) {
  const Stage s{1.0, {800.0, 0.06}, 0, 1e-4};
  const double f = 100.0;
  hc::HarmonicResonatorOptions o;
  o.max_between = 0.05;
  const Designed d = design(s, f, o);
  ASSERT_FALSE(d.harmonics.spec.empty());
  double highest_kept = 0.0, lowest_dropped = INFINITY;
  for (const hc::HarmonicChoice& h : d.harmonics.harmonics) {
    if (h.kept) highest_kept = std::max(highest_kept, h.frequency_hz);
    if (h.why.find("with the resonators below it") != std::string::npos) {
      lowest_dropped = std::min(lowest_dropped, h.frequency_hz);
    }
  }
  ASSERT_TRUE(std::isfinite(lowest_dropped)) << "the premise: together they do not settle";
  // None judged above the stage's first mode.
  double first_mode_hz = INFINITY;
  for (const hc::MeasuredMode& m : hc::measured_modes(measured(s))) {
    first_mode_hz = std::min(first_mode_hz, m.frequency_hz);
  }
  for (const hc::HarmonicChoice& h : d.harmonics.harmonics) {
    EXPECT_LE(h.frequency_hz, first_mode_hz) << h.harmonic;
  }
  EXPECT_GT(lowest_dropped, highest_kept);
  EXPECT_LE(d.harmonics.between, o.max_between);
  hc::FeedbackLaw with = d.loop;
  with.harmonics = d.harmonics.spec;
  const int ticks = static_cast<int>(std::lround(60.0 / (f * s.dt)));
  EXPECT_LT(error_rms(s, &with, f, ticks), error_rms(s, &d.loop, f, ticks));
}

// A tick more of delay (a DAQ's stale reading) turns a harmonic's phase by 360 f dt degrees:
// beyond the first ten harmonics only those it turns by at most 30 degrees are judged. On a
// 10 kHz loop a 20 Hz sine's first 30 (up to 600 Hz, 22 deg); on a 1 kHz loop a 10 Hz sine's
// first ten (from the 9th on, 32 deg and more).
TEST(HarmonicResonatorDesign, JudgeBeyondTheFirstTenOnlyWhereATickTurnsThePhaseLittle) {
  const auto highest = [](const Stage& s, double f) {
    const Designed d = design(s, f);
    std::size_t k = 0;
    for (const hc::HarmonicChoice& h : d.harmonics.harmonics) k = std::max(k, h.harmonic);
    return k;
  };
  EXPECT_EQ(highest(Stage{1.0, {3000.0, 0.06}, 0, 1e-4}, 20.0), 30u);
  EXPECT_EQ(highest(Stage{1.0, {3000.0, 0.06}, 0, 1e-3}, 10.0), 10u);
}

TEST(HarmonicResonatorDesign, RefusesNoResponseAndABadFundamental) {
  const Stage s{1.0, {3000.0, 0.06}, 0, 1e-4};
  hc::HarmonicResonatorOptions o;
  EXPECT_THROW(hc::design_harmonic_resonators({}, hc::FeedbackLaw{}, {}, o), std::invalid_argument);
  o.fundamental_hz = -1.0;
  EXPECT_THROW(hc::design_harmonic_resonators(measured(s), hc::FeedbackLaw{}, {}, o),
               std::invalid_argument);
  o.fundamental_hz = 10.0;
  o.max_tick_phase_deg = 0.0;
  EXPECT_THROW(hc::design_harmonic_resonators(measured(s), hc::FeedbackLaw{}, {}, o),
               std::invalid_argument);
}
