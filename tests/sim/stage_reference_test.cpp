#include "hystbench/sim/stage_reference.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace hs = hystbench::sim;

namespace {

const std::vector<hs::AxisRange> kXy = {{0.0, 45.0}, {2.0, 46.0}};

std::vector<std::unique_ptr<hs::SignalGenerator>> generators(const hs::StageReferenceSpec& spec,
                                                             std::span<const hs::AxisRange> r) {
  std::vector<std::unique_ptr<hs::SignalGenerator>> out;
  for (const hs::SignalSpec& s : hs::stage_reference(spec, r)) {
    out.push_back(hs::make_signal_generator(s));
  }
  return out;
}

std::string refusal(const hs::StageReferenceSpec& spec, std::span<const hs::AxisRange> r) {
  try {
    hs::stage_reference(spec, r);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(StageReference, ARasterSweepsTheFastAxisOnceALineAndStartsAtTheBottomCorner) {
  hs::StageReferenceSpec spec;  // 10 Hz fast, 0.1 Hz slow, 80 %
  const auto g = generators(spec, kXy);
  // The bottom corner of the 80 % span at t = 0.
  EXPECT_NEAR(g[0]->value(0.0), 22.5 - 18.0, 1e-9);
  EXPECT_NEAR(g[1]->value(0.0), 24.0 - 17.6, 1e-9);
  // The fast axis reaches its top after half its period, the slow axis after five seconds.
  EXPECT_NEAR(g[0]->value(0.05), 22.5 + 18.0, 1e-9);
  EXPECT_NEAR(g[1]->value(5.0), 24.0 + 17.6, 1e-9);
  // 50 lines per slow ramp: the fast axis turns 100 times in 5 s.
  int turns = 0;
  double last = g[0]->value(0.0), rising = 1.0;
  for (int k = 1; k <= 50000; ++k) {
    const double v = g[0]->value(k * 1e-4);
    if ((v - last) * rising < 0.0) {
      ++turns;
      rising = -rising;
    }
    last = v;
  }
  EXPECT_EQ(turns, 99);  // the 100th is the end of the 5 s
}

TEST(StageReference, ALissajousHasEachAxisAtItsFrequencyAndExtraAxesHoldTheirMiddle) {
  hs::StageReferenceSpec spec;
  spec.kind = hs::StageReferenceKind::kLissajous;
  spec.frequencies_hz = {10.0, 11.0};
  const std::vector<hs::AxisRange> three = {{0.0, 45.0}, {2.0, 46.0}, {-5.0, 5.0}};
  const auto g = generators(spec, three);
  for (const double t : {0.0123, 0.31, 0.777}) {
    EXPECT_NEAR(g[0]->value(t), 22.5 + 18.0 * std::sin(2.0 * M_PI * 10.0 * t), 1e-9);
    EXPECT_NEAR(g[1]->value(t), 24.0 + 17.6 * std::sin(2.0 * M_PI * 11.0 * t), 1e-9);
    EXPECT_EQ(g[2]->value(t), 0.0);
  }
  // One common period: both back where they started after 1 s.
  EXPECT_NEAR(g[0]->value(1.0), g[0]->value(0.0), 1e-9);
  EXPECT_NEAR(g[1]->value(1.0), g[1]->value(0.0), 1e-9);
}

TEST(StageReference, ASpiralShrinksLinearlyToTheMiddle) {
  hs::StageReferenceSpec spec;
  spec.kind = hs::StageReferenceKind::kSpiral;
  spec.frequencies_hz = {5.0};
  spec.duration_s = 4.0;
  const auto g = generators(spec, kXy);
  const auto radius = [&](double t) {  // relative to the full span's half
    const double x = (g[0]->value(t) - 22.5) / 18.0, y = (g[1]->value(t) - 24.0) / 17.6;
    return std::hypot(x, y);
  };
  for (const double t : {0.0, 1.0, 2.03, 3.5}) EXPECT_NEAR(radius(t), 1.0 - t / 4.0, 1e-9) << t;
  EXPECT_NEAR(radius(4.5), 0.0, 1e-9);
}

TEST(StageReference, BadSpecsAreRefusedNamingTheField) {
  hs::StageReferenceSpec spec;
  const std::vector<hs::AxisRange> one = {{0.0, 45.0}};
  EXPECT_EQ(refusal(spec, one), "axes: raster moves 2 axes, the stage has 1");
  spec.frequencies_hz = {10.0};
  EXPECT_EQ(refusal(spec, kXy), "frequencies_hz: raster takes 2, got 1");
  spec.frequencies_hz = {10.0, -1.0};
  EXPECT_EQ(refusal(spec, kXy), "frequencies_hz[1]: must be > 0");
  spec.frequencies_hz = {10.0, 0.1};
  spec.span_fraction = 1.5;
  EXPECT_EQ(refusal(spec, kXy), "span_fraction: must be in (0, 1]");
  spec.span_fraction = 0.8;
  spec.kind = hs::StageReferenceKind::kLissajous;
  spec.frequencies_hz = {10.0, 11.0, 12.0};
  EXPECT_EQ(refusal(spec, kXy), "axes: lissajous moves 3 axes, the stage has 2");
  const std::vector<hs::AxisRange> empty = {{0.0, 45.0}, {3.0, 3.0}};
  spec.frequencies_hz = {10.0, 11.0};
  EXPECT_EQ(refusal(spec, empty), "ranges[1]: max must be greater than min");
  EXPECT_THROW(hs::stage_reference_kind_from_string("zigzag"), std::invalid_argument);
  EXPECT_EQ(hs::stage_reference_kind_from_string("spiral"), hs::StageReferenceKind::kSpiral);
}
