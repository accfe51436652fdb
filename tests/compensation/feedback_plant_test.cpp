#include "hystbench/compensation/feedback_plant.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

#include "hystbench/compensation/pi_model.hpp"

namespace hc = hystbench::compensation;

namespace {

constexpr double kRate = 1000.0;

hc::ActuatorModel pi_model(std::vector<double> thresholds, std::vector<double> weights) {
  hc::ActuatorModel m(std::make_unique<hc::PiModel>(
      hc::PiParameters{std::move(thresholds), std::move(weights), 0.0}));
  m.input_min = 0.0;
  m.input_max = 10.0;
  m.configure(1.0 / kRate);
  return m;
}

// A small sine at rest around mid-range (its peak below the first non-zero threshold), four
// periods of 100 samples at lines 1 and 3; the model's own response to it stands for the measured
// one.
struct SmallSignal {
  std::vector<double> drive;
  std::vector<hc::MeasuredResponse> measured;
  std::vector<hc::ResponseSegment> segments;
};

SmallSignal small_signal(const hc::ActuatorModel& model) {
  SmallSignal s;
  const std::size_t period = 100, periods = 4;
  for (std::size_t k = 0; k < period * periods; ++k) {
    const double phase =
        2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(period);
    s.drive.push_back(5.0 + 0.2 * std::sin(phase) + 0.05 * std::sin(3.0 * phase));
  }
  hc::ActuatorModel m = model;
  const std::vector<double> y = m.simulate(s.drive, 1.0 / kRate);
  const std::vector<std::size_t> lines = {1, 3};
  s.measured.push_back(hc::estimate_response(s.drive, y, period, lines, kRate));
  s.segments.push_back({0, period, periods});
  return s;
}

}  // namespace

// Plays whose weights add up as the branch climbs: at rest a small signal moves only the first
// (slope 0.2), along the loop all four (1.1). The scale is their ratio.
TEST(MotionScale, IsTheSteepestBranchOverTheSlopeAtRest) {
  const hc::ActuatorModel model = pi_model({0.0, 1.0, 2.0, 3.0}, {0.2, 0.3, 0.3, 0.3});
  const SmallSignal s = small_signal(model);
  ASSERT_NEAR(std::abs(s.measured[0].response[0]), 0.2, 1e-6);
  const hc::MotionScale m = hc::motion_scale(s.measured, s.segments, model, s.drive, kRate);
  EXPECT_EQ(m.response, 0u);
  EXPECT_NEAR(m.ratio, 1.1 / 0.2, 0.02 * 1.1 / 0.2);
}

// A stage without hysteresis climbs as it answers at rest: no scale.
TEST(MotionScale, IsOneWhereTheBranchIsNoSteeperThanTheSlopeAtRest) {
  const hc::ActuatorModel model = pi_model({0.0}, {0.7});
  const SmallSignal s = small_signal(model);
  EXPECT_NEAR(hc::motion_scale(s.measured, s.segments, model, s.drive, kRate).ratio, 1.0, 1e-9);
  hc::ActuatorModel no_range = pi_model({0.0, 1.0}, {0.2, 0.5});
  no_range.input_max = no_range.input_min;
  EXPECT_EQ(hc::motion_scale(s.measured, s.segments, no_range, s.drive, kRate).ratio, 1.0);
}
