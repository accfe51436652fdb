#include "hystbench/compensation/delay_line.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/dynamics_inversion.hpp"
#include "hystbench/compensation/pi_model.hpp"

namespace hc = hystbench::compensation;

namespace {

std::vector<double> pushed(hc::DelayLine line, const std::vector<double>& x) {
  line.reset(x.front());
  std::vector<double> out;
  for (const double v : x) out.push_back(line.push(v));
  return out;
}

}  // namespace

TEST(DelayLine, AFractionInterpolatesBetweenTheTwoSamplesAroundIt) {
  std::vector<double> x;
  for (int k = 0; k < 50; ++k) x.push_back(static_cast<double>(k * k % 17) - 3.0);
  const auto whole2 = pushed(hc::DelayLine(2), x);
  const auto whole3 = pushed(hc::DelayLine(3), x);
  const auto frac = pushed(hc::DelayLine::of(2.25), x);
  for (std::size_t k = 0; k < x.size(); ++k) {
    ASSERT_NEAR(frac[k], 0.75 * whole2[k] + 0.25 * whole3[k], 1e-12) << k;
  }
  for (std::size_t k = 2; k < x.size(); ++k) ASSERT_EQ(whole2[k], x[k - 2]);
}

TEST(DelayLine, WithinRoundingOfAWholeNumberItIsWhole) {
  EXPECT_EQ(hc::DelayLine::of(3.0 - 1e-12).samples(), 3u);
  EXPECT_EQ(hc::DelayLine::of(3.0 - 1e-12).fraction(), 0.0);
  EXPECT_EQ(hc::DelayLine::of(0.4).samples(), 0u);
  EXPECT_DOUBLE_EQ(hc::DelayLine::of(0.4).fraction(), 0.4);
  EXPECT_EQ(hc::DelayLine::of(-1.0).samples(), 0u);
}

TEST(DelayLine, AModelKeepsAFractionalDelayAndItsInversionPreviewsIt) {
  hc::ActuatorModel model(
      std::make_unique<hc::PiModel>(hc::PiParameters{{0.0, 1.0}, {0.3, 0.1}, 0}));
  model.set_delay(2.5e-4);
  model.configure(1e-4);
  EXPECT_DOUBLE_EQ(model.delay_s(), 2.5e-4);
  EXPECT_EQ(model.delay_samples(), 3u);  // nearest whole sample
  // A ramp through a play past its threshold is affine: the fraction delays it by 2.5 samples.
  std::vector<double> u;
  for (int k = 0; k < 200; ++k) u.push_back(0.01 * k);
  const auto y = model.simulate(u, 1e-4);
  hc::ActuatorModel undelayed(model);
  undelayed.set_delay(0.0);
  const auto y0 = undelayed.simulate(u, 1e-4);
  for (std::size_t k = 150; k < u.size(); ++k) {
    ASSERT_NEAR(y[k], 0.5 * (y0[k - 2] + y0[k - 3]), 1e-12) << k;
  }
  const hc::DynamicsInversion inversion(model, 1e-4);
  EXPECT_DOUBLE_EQ(inversion.lead_s(), 2.5e-4);
  EXPECT_EQ(inversion.preview_samples(), 3);
}
