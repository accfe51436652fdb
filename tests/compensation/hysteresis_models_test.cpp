// Properties of the forward models: play definition, wiping-out, rate independence, asymmetry.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/play_operator.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;

TEST(PlayOperator, FollowsDefinitionAndHoldsInsideBand) {
  hc::PlayOperator play(1.0, 0.0);
  EXPECT_DOUBLE_EQ(play.step(0.5), 0.0);   // inside [u-r, u+r]: holds
  EXPECT_DOUBLE_EQ(play.step(3.0), 2.0);   // pushed up: u - r
  EXPECT_DOUBLE_EQ(play.step(2.5), 2.0);   // reversal inside the band: holds
  EXPECT_DOUBLE_EQ(play.step(-1.0), 0.0);  // pushed down: u + r
  EXPECT_DOUBLE_EQ(play.peek(5.0), 4.0);
  EXPECT_DOUBLE_EQ(play.output(), 0.0);  // peek does not change state
  EXPECT_THROW(hc::PlayOperator(-1.0), std::invalid_argument);
}

TEST(PiModel, IsWeightedSumOfPlaysPlusOffset) {
  hc::PiModel pi({{0.0, 1.0, 2.0}, {0.5, 0.3, 0.2}, 7.0});
  pi.reset(0.0);
  hc::PlayOperator p0(0.0), p1(1.0), p2(2.0);
  for (double u : {0.0, 2.0, 5.0, 3.0, 4.5, -1.0, 0.25}) {
    const double expected = 7.0 + 0.5 * p0.step(u) + 0.3 * p1.step(u) + 0.2 * p2.step(u);
    EXPECT_NEAR(pi.step(u), expected, 1e-12);
  }
}

TEST(PiModel, RejectsBadParametersNamingTheField) {
  auto message = [](const hc::PiParameters& p) {
    try {
      hc::PiModel m(p);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({{0.0, 2.0, 1.0}, {1, 1, 1}, 0}).find("play.thresholds"), std::string::npos);
  EXPECT_NE(message({{0.0, 1.0}, {1.0}, 0}).find("play.weights"), std::string::npos);
  EXPECT_NE(message({{0.0, 1.0}, {1.0, NAN}, 0}).find("play.weights[1]"), std::string::npos);
}

// After the input passes a previous extremum, the memory of the loops inside it is erased: two
// histories that differ only inside a wiped-out excursion give identical outputs afterwards.
TEST(PiModel, WipingOutProperty) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const auto params = hystbench::testing::random_mpi(rng, 12, 3, 10.0);
    hc::ModifiedPiModel a(params), b(params);
    a.reset(0.0);
    b.reset(0.0);
    auto ramp = [](hc::ModifiedPiModel& m, double from, double to) {
      for (int k = 1; k <= 50; ++k) m.step(from + (to - from) * k / 50.0);
    };
    ramp(a, 0.0, 10.0), ramp(b, 0.0, 10.0);
    ramp(a, 10.0, 1.0), ramp(b, 10.0, 1.0);
    // a: nested minor loops below 8; b: straight up.
    ramp(a, 1.0, 6.0), ramp(a, 6.0, 3.0), ramp(a, 3.0, 5.0), ramp(a, 5.0, 4.0), ramp(a, 4.0, 8.0);
    ramp(b, 1.0, 8.0);
    std::uniform_real_distribution<double> unit(0.0, 10.0);
    for (int k = 0; k < 500; ++k) {
      const double u = unit(rng);
      ASSERT_NEAR(a.step(u), b.step(u), 1e-9) << "trial " << trial << " sample " << k;
    }
  }
}

// Rate independence: the loop height at mid-input does not depend on the sample rate.
TEST(PiModel, LoopHeightIndependentOfSampleRate) {
  std::mt19937_64 rng(11);
  const auto params = hystbench::testing::random_mpi(rng, 20, 4, 100.0);
  std::vector<double> heights;
  for (const double fs : {100.0, 1000.0, 10000.0}) {
    hc::ModifiedPiModel m(params);
    m.reset(0.0);
    // Triangle 0 -> 100 -> 0 over 1 s, two periods; mid-input sampled exactly at t=.25 and .75.
    double up = 0.0, down = 0.0;
    const int n = static_cast<int>(2 * fs);
    for (int k = 0; k <= n; ++k) {
      const double t = k / fs;
      const double phase = std::fmod(t, 1.0);
      const double u = phase < 0.5 ? 200.0 * phase : 200.0 * (1.0 - phase);
      const double y = m.step(u);
      if (k == static_cast<int>(1.25 * fs)) up = y;
      if (k == static_cast<int>(1.75 * fs)) down = y;
    }
    heights.push_back(down - up);
  }
  EXPECT_GT(heights[0], 0.0);
  EXPECT_NEAR(heights[1], heights[0], 1e-9 * std::abs(heights[0]));
  EXPECT_NEAR(heights[2], heights[0], 1e-9 * std::abs(heights[0]));
}

TEST(ModifiedPiModel, DeadZonesMakeTheLoopAsymmetric) {
  hc::PiParameters play{{0.0, 2.0, 4.0}, {0.6, 0.3, 0.2}, 0.0};
  hc::ModifiedPiModel sym({play, {{0.0}, {1.0}}, 5.0});
  hc::ModifiedPiModel asym({play, {{-3.0, 0.0, 3.0}, {0.0, 1.0, 0.5}}, 5.0});
  // Identity dead zone: same as the PI.
  hc::PiModel pi(play);
  sym.reset(0.0), pi.reset(0.0), asym.reset(0.0);
  double max_diff = 0.0;
  for (int k = 0; k <= 200; ++k) {
    const double u = 10.0 * std::sin(0.05 * k);
    EXPECT_NEAR(sym.step(u), pi.step(u), 1e-12);
    max_diff = std::max(max_diff, std::abs(asym.step(u) - pi.peek(u)));
  }
  EXPECT_GT(max_diff, 0.1);
}

TEST(DeadZoneSuperposition, InverseUndoesTheMapOnBothSides) {
  hc::DeadZoneSuperposition s({{-2.0, -1.0, 0.0, 1.5, 3.0}, {0.3, -0.2, 1.0, 0.4, -0.5}});
  ASSERT_TRUE(s.invertibility().invertible);
  const auto inv = s.inverse();
  for (double v = -6.0; v <= 6.0; v += 0.01) EXPECT_NEAR(inv.apply(s.apply(v)), v, 1e-12);
  hc::DeadZoneSuperposition bad({{0.0, 1.0}, {1.0, -1.5}});
  const auto why = bad.invertibility();
  EXPECT_FALSE(why.invertible);
  EXPECT_EQ(why.block, "deadzone");
  EXPECT_EQ(why.index, 1);
  EXPECT_THROW(bad.inverse(), hc::NotInvertibleError);
}

// slope() is the derivative of apply() between thresholds, on both sides of 0.
TEST(DeadZoneSuperposition, SlopeIsTheDerivativeOfTheMap) {
  const hc::DeadZoneSuperposition s(
      hc::DeadZoneParameters{{-15.0, -5.0, 0.0, 12.0}, {0.15, 0.1, 1.0, 0.4}});
  for (const double v : {-20.0, -10.0, -1.0, 3.0, 11.0, 13.0, 30.0}) {
    const double h = 1e-6;
    EXPECT_NEAR(s.slope(v), (s.apply(v + h) - s.apply(v - h)) / (2 * h), 1e-6) << v;
  }
  EXPECT_DOUBLE_EQ(s.slope(-20.0), 1.25);
  EXPECT_DOUBLE_EQ(s.slope(3.0), 1.0);
  EXPECT_DOUBLE_EQ(s.slope(13.0), 1.4);
}

TEST(DeadZoneSuperposition, UniformThresholdsSpreadEachSideEvenlyAndAreAccepted) {
  // m = 3 on an output range 4 below and 8 above the center: steps of 1 and 2.
  const auto d = hc::uniform_dead_zone_thresholds(3, 4.0, 8.0);
  EXPECT_EQ(d, (std::vector<double>{-3.0, -2.0, -1.0, 0.0, 2.0, 4.0, 6.0}));
  EXPECT_EQ(hc::uniform_dead_zone_thresholds(0, 4.0, 8.0), std::vector<double>{0.0});
  // Strictly increasing with one zero: a superposition takes them as they are.
  EXPECT_NO_THROW(hc::DeadZoneSuperposition({d, std::vector<double>(d.size(), 0.1)}));
}

TEST(CoupledPlayPiModel, WidthDependsOnDirectionAndLevel) {
  // Rising above rc = 1 uses r = 0.5; below it the width is rc. Falling below -rb = -1 uses ra.
  const double r = 0.5, ra = 2.0, rb = 1.0, rc = 1.0;
  double z = 0.0;
  z = hc::CoupledPlayPiModel::operator_output(0.8, 0.0, z, r, ra, rb, rc);
  EXPECT_DOUBLE_EQ(z, 0.0);  // max(0, 0.8 - 1.0)
  z = hc::CoupledPlayPiModel::operator_output(3.0, 0.8, z, r, ra, rb, rc);
  EXPECT_DOUBLE_EQ(z, 2.5);
  z = hc::CoupledPlayPiModel::operator_output(1.0, 3.0, z, r, ra, rb, rc);
  EXPECT_DOUBLE_EQ(z, 2.0);  // min(2.5, 1.0 + rb)
  z = hc::CoupledPlayPiModel::operator_output(-3.0, 1.0, z, r, ra, rb, rc);
  EXPECT_DOUBLE_EQ(z, -1.0);  // min(2.0, -3.0 + ra)
}

TEST(CoupledPlayPiModel, StepAndPeekAreTheWeightedSumOfItsOperators) {
  // The model's vectorised kernel against the operator definition, one operator at a time, for
  // operator counts that do and do not fill whole vectors, over a random signal with reversals.
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> width(0.0, 3.0), weight(0.05, 1.0), input(-8.0, 8.0);
  for (const std::size_t n : {1u, 4u, 7u, 13u, 50u}) {
    hc::CoupledPlayParameters p;
    for (std::size_t i = 0; i < n; ++i) {
      p.r.push_back(width(rng));
      p.rc.push_back(p.r.back() + width(rng));
      p.rb.push_back(width(rng));
      p.ra.push_back(p.rb.back() * 0.5);
      p.weights.push_back(weight(rng));
    }
    p.offset = 0.3;
    hc::CoupledPlayPiModel model(p);
    model.reset(0.0);
    std::vector<double> z(n, 0.0);
    double u_prev = 0.0;
    for (int k = 0; k < 2000; ++k) {
      const double u = k % 7 == 0 ? input(rng) : u_prev + 0.1 * input(rng);
      double expected = p.offset;
      for (std::size_t i = 0; i < n; ++i) {
        z[i] = hc::CoupledPlayPiModel::operator_output(u, u_prev, z[i], p.r[i], p.ra[i], p.rb[i],
                                                       p.rc[i]);
        expected += p.weights[i] * z[i];
      }
      const double peeked = model.peek(u);
      const double stepped = model.step(u);
      ASSERT_NEAR(stepped, expected, 1e-12 * (1.0 + std::abs(expected))) << "n " << n << " k " << k;
      ASSERT_EQ(peeked, stepped) << "n " << n << " k " << k;
      u_prev = u;
    }
  }
}

TEST(RateDependentPiModel, ReducesToModifiedPiAtZeroRateCoefficients) {
  std::mt19937_64 rng(3);
  const auto base = hystbench::testing::random_mpi(rng, 10, 2, 20.0);
  hc::RateDependentPiModel rate({base, std::vector<double>(10, 0.0), 100.0}, 1e-3);
  hc::ModifiedPiModel mpi(base);
  rate.reset(0.0), mpi.reset(0.0);
  for (double u : hystbench::testing::random_reversal_signal(rng, 2000, 0.0, 20.0)) {
    ASSERT_NEAR(rate.step(u), mpi.step(u), 1e-12);
  }
}

// The signed rate (the rate-dependent paper's eq. 16) raises the loading branch and lowers the
// unloading one; its output is smooth through a reversal of a smooth input, where |du/dt| puts a
// corner (the weights jump back up as the rate's magnitude turns).
TEST(RateDependentPiModel, TheSignedLawIsSmoothThroughAReversalWhereTheMagnitudeHasACorner) {
  hc::ModifiedPiParameters base{
      {{0.0, 2.0, 4.0, 6.0}, {0.5, 0.2, 0.2, 0.1}, 0.0}, {{0.0}, {1.0}}, 0.0};
  const double dt = 1e-4;
  auto run = [&](hc::RateLaw law, double* rising, double* falling) {
    hc::RateDependentPiParameters p{base, {0.0, 0.001, 0.002, 0.003}, 1e4};
    p.rate_law = law;
    hc::RateDependentPiModel m(p, dt);
    m.reset(0.0);
    std::vector<double> y;
    for (int k = 0; k <= 2000; ++k) {  // 5 Hz sine 0..40, one period
      y.push_back(m.step(20.0 - 20.0 * std::cos(2.0 * std::numbers::pi * 5.0 * k * dt)));
    }
    *rising = y[500];     // u = 20 rising
    *falling = y[1500];   // u = 20 falling
    double corner = 0.0;  // largest second difference around the top (k = 1000)
    for (int k = 990; k <= 1010; ++k)
      corner = std::max(corner, std::abs(y[k + 1] - 2 * y[k] + y[k - 1]));
    return corner;
  };
  double up_s = 0, down_s = 0, up_m = 0, down_m = 0;
  const double corner_signed = run(hc::RateLaw::kSigned, &up_s, &down_s);
  const double corner_magnitude = run(hc::RateLaw::kMagnitude, &up_m, &down_m);
  EXPECT_GT(corner_magnitude, 20.0 * corner_signed);
  // The same law on the loading branch; unloading the signed one lowers the output instead.
  EXPECT_NEAR(up_s, up_m, 1e-9);
  EXPECT_LT(down_s, down_m - 0.1);
}

TEST(RateDependentPiModel, TheSignedLawIsCheckedAtTheFastestFallToo) {
  hc::ModifiedPiParameters base{{{0.0, 2.0}, {0.5, 0.2}, 0.0}, {{0.0}, {1.0}}, 0.0};
  // W_0(rate) = 0.5 + 1e-4 rate: positive on [0, 1e4], not at -1e4.
  hc::RateDependentPiParameters p{base, {1e-4, 1e-4}, 1e4};
  EXPECT_TRUE(hc::RateDependentPiModel(p, 1e-4).invertibility().invertible);
  p.rate_law = hc::RateLaw::kSigned;
  const hc::Invertibility v = hc::RateDependentPiModel(p, 1e-4).invertibility();
  EXPECT_FALSE(v.invertible);
  EXPECT_NE(v.reason.find("at rate -"), std::string::npos) << v.reason;
  // Capped at +-max_rate: a faster fall reads as -max_rate.
  p.rate_coefficients = {1e-5, 1e-5};
  hc::RateDependentPiModel m(p, 1e-4);
  m.reset(5.0);
  EXPECT_DOUBLE_EQ(m.peek_at_rate(5.0, -1e6), m.peek_at_rate(5.0, -1e4));
  EXPECT_LT(m.peek_at_rate(5.0, -1e4), m.peek_at_rate(5.0, 0.0));
}

TEST(RateDependentPiModel, LoopWidensWithRateWhenCoefficientsArePositive) {
  hc::ModifiedPiParameters base{
      {{0.0, 2.0, 4.0, 6.0}, {0.5, 0.2, 0.2, 0.1}, 0.0}, {{0.0}, {1.0}}, 0.0};
  auto width_at = [&](double frequency_hz) {
    hc::RateDependentPiModel m({base, {0.0, 0.001, 0.002, 0.003}, 1e4}, 1e-4);
    m.reset(0.0);
    double up = 0, down = 0;
    const int n = static_cast<int>(2.0 / frequency_hz / 1e-4);
    for (int k = 0; k <= n; ++k) {
      const double t = k * 1e-4 * frequency_hz;  // cycles
      const double phase = std::fmod(t, 1.0);
      const double u = phase < 0.5 ? 40.0 * phase : 40.0 * (1.0 - phase);
      const double y = m.step(u);
      if (k == static_cast<int>(1.25 / frequency_hz / 1e-4)) up = y;
      if (k == static_cast<int>(1.75 / frequency_hz / 1e-4)) down = y;
    }
    return down - up;
  };
  EXPECT_GT(width_at(10.0), width_at(1.0) * 1.05);
}
