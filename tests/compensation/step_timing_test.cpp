#include "hystbench/compensation/step_timing.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "hystbench/compensation/delay_line.hpp"
#include "hystbench/compensation/second_order_dynamics.hpp"

namespace hc = hystbench::compensation;

namespace {

constexpr double kDt = 1e-4;

// Holds and steps between levels, with 50 ms ramps between them; y = G[delay[f(u)]] with f a
// static curve, plus a "shape" term that only ramps carry (as a loop the model misses does) and
// noise.
struct Record {
  std::vector<double> u, y;
};
Record record(double fn, double zeta, double delay, double shape, bool steps) {
  Record r;
  const double levels[] = {10.0, 120.0, 60.0, 140.0, 0.0, 90.0};
  double last = 0.0;
  for (const double level : levels) {
    // A ramp to near the level and a hold; then, with steps, a jump to the level and a hold.
    const double target = steps ? level + (level < 75.0 ? 30.0 : -30.0) : level;
    for (int k = 0; k < 500; ++k) r.u.push_back(last + (target - last) * (k + 1) / 500.0);
    for (int k = 0; k < 1000; ++k) r.u.push_back(target);
    if (steps) r.u.insert(r.u.end(), 1000, level);
    last = r.u.back();
  }
  hc::DelayLine line = hc::DelayLine::of(delay);
  hc::SecondOrderDynamics mode({fn, zeta}, kDt);
  const auto f = [](double v) { return 0.3 * v - 4e-4 * v * v; };
  line.reset(f(r.u[0]));
  mode.reset(f(r.u[0]));
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.005);
  for (std::size_t k = 0; k < r.u.size(); ++k) {
    const double rate = k > 0 ? (r.u[k] - r.u[k - 1]) / kDt : 0.0;
    const double ramp_shape = std::abs(rate) < 1e4 ? shape * rate * 1e-3 : 0.0;
    r.y.push_back(mode.step(line.push(f(r.u[k]))) + ramp_shape + noise(rng));
  }
  return r;
}

}  // namespace

TEST(StepTiming, RecoversAFractionalDelayAndTheModeFromTheStepsWhateverTheShapeElsewhere) {
  for (const double shape : {0.0, 2.0}) {
    const Record r = record(800.0, 0.06, 2.4, shape, true);
    const auto t = hc::fit_step_timing(r.u, r.y, kDt, {1100.0, 0.2, 1.0});
    ASSERT_TRUE(t.has_value());
    EXPECT_EQ(t->steps, 6u);  // one a level
    EXPECT_NEAR(t->natural_frequency_hz, 800.0, 4.0) << "shape " << shape;
    EXPECT_NEAR(t->damping_ratio, 0.06, 0.004) << "shape " << shape;
    EXPECT_NEAR(t->delay_samples, 2.4, 0.03) << "shape " << shape;
    EXPECT_LT(t->rms, 0.01);  // the noise
  }
}

TEST(StepTiming, NothingWithoutSteps) {
  const Record r = record(800.0, 0.06, 2.4, 0.0, false);
  EXPECT_FALSE(hc::fit_step_timing(r.u, r.y, kDt, {1100.0, 0.2, 1.0}).has_value());
  EXPECT_FALSE(hc::fit_step_timing(r.u, std::vector<double>(3), kDt, {1100.0, 0.2, 1.0}));
}

// A record-wide fit can put the mode far below the one the steps show: started at a quarter of
// it, the mode is still found.
TEST(StepTiming, FindsAModeFarAboveTheStart) {
  const Record r = record(3000.0, 0.06, 2.5, 2.0, true);
  const auto t = hc::fit_step_timing(r.u, r.y, kDt, {720.0, 0.56, 2.0});
  ASSERT_TRUE(t.has_value());
  EXPECT_NEAR(t->natural_frequency_hz, 3000.0, 15.0);
  EXPECT_NEAR(t->damping_ratio, 0.06, 0.004);
  EXPECT_NEAR(t->delay_samples, 2.5, 0.03);
}
