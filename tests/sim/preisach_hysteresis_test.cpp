// The Preisach model of the simulated actuator: its Everett table, its memory (wiping out, return
// points, congruent minor loops) and its relaxed state.
#include "hystbench/sim/preisach_hysteresis.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace hs = hystbench::sim;

namespace {

/// Steps h through `inputs`, each approached in small steps; returns the output at each.
std::vector<double> visit(hs::PreisachHysteresis& h, const std::vector<double>& inputs) {
  std::vector<double> out;
  double u = inputs.front();
  h.step(u);
  for (const double target : inputs) {
    const int n = 200;
    const double from = u;
    for (int k = 1; k <= n; ++k) h.step(from + (target - from) * k / n);
    u = target;
    out.push_back(h.output());
  }
  return out;
}

/// The branch from the present state along inputs from..to, sampled at `n` points.
std::vector<double> branch(hs::PreisachHysteresis& h, double from, double to, int n) {
  std::vector<double> y;
  for (int k = 0; k <= n; ++k) y.push_back(h.step(from + (to - from) * k / n));
  return y;
}

}  // namespace

TEST(PreisachHysteresis, TheEverettTableConvergesWithItsGrid) {
  hs::PreisachParameters p;
  const hs::PreisachHysteresis coarse(p);
  p.grid_points = 4097;
  const hs::PreisachHysteresis fine(p);
  double worst = 0.0;
  for (double a = 0.0; a <= 150.0; a += 3.7) {
    for (double b = 0.0; b <= a; b += 2.9) {
      worst = std::max(worst, std::abs(coarse.everett(a, b) - fine.everett(a, b)));
    }
  }
  EXPECT_LT(worst, 1e-3 * p.switching_um);
  EXPECT_NEAR(coarse.everett(150.0, 0.0), p.switching_um, 1e-12);
  EXPECT_EQ(coarse.everett(40.0, 40.0), 0.0);
  EXPECT_EQ(coarse.everett(40.0, 60.0), 0.0);
  // More relays inside a larger triangle.
  EXPECT_LT(coarse.everett(80.0, 20.0), coarse.everett(90.0, 20.0));
  EXPECT_LT(coarse.everett(80.0, 20.0), coarse.everett(80.0, 10.0));
}

TEST(PreisachHysteresis, SaturatesAtTheEndsOfTheRange) {
  hs::PreisachParameters p;
  hs::PreisachHysteresis h(p);
  EXPECT_EQ(h.output(), 0.0);  // relaxed at u_min: every relay down
  EXPECT_NEAR(h.step(150.0), p.switching_um, 1e-12);
  EXPECT_EQ(h.step(0.0), 0.0);
  EXPECT_EQ(h.memory_size(), 0u);
  EXPECT_EQ(h.step(500.0), h.step(150.0));  // inputs beyond the range are clamped
}

TEST(PreisachHysteresis, ReturnsToTheBranchItLeftAndWipesOutTheLoopsItPasses) {
  hs::PreisachHysteresis h{hs::PreisachParameters{}};
  h.reset(0.0);
  // 0 -> 100 -> 40 -> 80 -> 40 (the minor loop closes) -> 120 (it is wiped out).
  const auto y = visit(h, {0.0, 100.0, 40.0, 80.0, 40.0, 120.0});
  EXPECT_NEAR(y[4], y[2], 1e-12) << "return-point memory: back at 40 V the output is as before";
  EXPECT_EQ(h.memory_size(), 0u);  // one rising branch from the bottom is left
  hs::PreisachHysteresis direct{hs::PreisachParameters{}};
  direct.reset(0.0);
  const auto z = visit(direct, {0.0, 120.0});
  EXPECT_NEAR(y[5], z[1], 1e-12) << "passing 100 V again wipes out every loop inside it";
  EXPECT_GT(y[1] - y[3], 0.0);
}

TEST(PreisachHysteresis, MinorLoopsBetweenTheSameInputsAreCongruent) {
  // The Preisach property a modified PI (a PI followed by a static output map) lacks: the loop
  // between the same two inputs has the same shape wherever the history puts it.
  hs::PreisachHysteresis a{hs::PreisachParameters{}};
  hs::PreisachHysteresis b{hs::PreisachParameters{}};
  a.reset(0.0);
  b.reset(0.0);
  visit(a, {0.0, 150.0, 60.0});
  visit(b, {0.0, 100.0, 60.0});
  const auto up_a = branch(a, 60.0, 90.0, 30), up_b = branch(b, 60.0, 90.0, 30);
  EXPECT_GT(std::abs(up_a.front() - up_b.front()), 0.5);  // different levels
  for (std::size_t k = 0; k < up_a.size(); ++k) {
    ASSERT_NEAR(up_a[k] - up_a.front(), up_b[k] - up_b.front(), 1e-9) << k;
  }
}

TEST(PreisachHysteresis, TheOutputIsContinuousThroughReversals) {
  hs::PreisachHysteresis h{hs::PreisachParameters{}};
  h.reset(30.0);
  double u = 30.0, y = h.output(), worst = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double next = 75.0 + 60.0 * std::sin(k * 0.003) * std::cos(k * 0.0007);
    const double y_next = h.step(next);
    // Slope at most every relay switching at once at one alpha: bounded by the table's.
    worst = std::max(worst, std::abs(y_next - y) / std::max(std::abs(next - u), 1e-12));
    u = next;
    y = y_next;
  }
  EXPECT_LT(worst, 1.0);  // µm/V: the relays' share of the slope never jumps
}

TEST(PreisachHysteresis, ResetRelaxesAtTheInputAndRepeats) {
  hs::PreisachParameters p;
  hs::PreisachHysteresis h(p);
  h.reset(75.0);
  const double relaxed = h.output();
  // Between the ascending branch from the bottom and the descending one from the top.
  hs::PreisachHysteresis up(p), down(p);
  up.reset(0.0);
  const double ascending = visit(up, {0.0, 75.0}).back();
  visit(down, {0.0, 150.0});
  const double descending = visit(down, {150.0, 75.0}).back();
  EXPECT_GT(relaxed, ascending + 0.1);
  EXPECT_LT(relaxed, descending - 0.1);
  EXPECT_LT(h.memory_size(), 100u);
  h.step(20.0);
  h.step(140.0);
  h.reset(75.0);
  EXPECT_EQ(h.output(), relaxed);
}

TEST(PreisachHysteresis, AFullMemoryMergesItsInnermostLoopAndStaysBounded) {
  hs::PreisachHysteresis h{hs::PreisachParameters{}};
  h.reset(0.0);
  h.step(150.0);
  // A converging oscillation: every reversal is a new, smaller, nested extremum.
  double amplitude = 70.0;
  for (std::size_t k = 0; k < 3 * hs::PreisachHysteresis::kMemoryCapacity; ++k) {
    h.step(75.0 + ((k % 2) ? amplitude : -amplitude));
    amplitude *= 0.999;
    ASSERT_LE(h.memory_size(), hs::PreisachHysteresis::kMemoryCapacity);
    ASSERT_TRUE(h.output() >= 0.0 && h.output() <= h.parameters().switching_um);
  }
  EXPECT_GT(h.memory_overflows(), 0u);
}

TEST(PreisachHysteresis, RejectsBadParametersNamingThem) {
  hs::PreisachParameters p;
  p.bias_std_v = 0.0;
  try {
    hs::PreisachHysteresis h(p);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bias_std_v"), std::string::npos) << e.what();
  }
  p = {};
  p.bias_mean_v = 5000.0;  // every relay far above the range
  p.bias_std_v = 1.0;
  EXPECT_THROW(hs::PreisachHysteresis{p}, std::invalid_argument);
}
