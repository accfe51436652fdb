#include "hystbench/sim/major_loop_metrics.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace hs = hystbench::sim;

namespace {

/// Only a classical PI: every other effect off, identity dead zone.
hs::SimulatedActuatorConfig pi_only(std::vector<double> thresholds, std::vector<double> weights) {
  hs::SimulatedActuatorConfig c = hs::SimulatedActuatorConfig::modified_pi_truth();
  c.hysteresis.play_thresholds_v = std::move(thresholds);
  c.hysteresis.play_weights_um_per_v = std::move(weights);
  c.hysteresis.play_offset_um = 0.0;
  c.hysteresis.dead_zone_thresholds_um = {0.0};
  c.hysteresis.dead_zone_weights = {1.0};
  c.creep.enabled = false;
  c.dynamics.enabled = false;
  c.sensor_noise.enabled = false;
  c.dac.enabled = false;
  c.adc.enabled = false;
  return c;
}

}  // namespace

TEST(MajorLoopMetrics, MatchesTheClassicalPiLoopInClosedForm) {
  // On a periodic 0..U cycle, play r (< U/2) spans r .. U - r and its branches at U/2 are
  // U/2 - r apart from either side: width min(2r, U - 2r), range contribution U - 2r.
  const std::vector<double> r = {0.0, 20.0, 50.0}, w = {0.2, 0.1, 0.05};
  const double span = 150.0;
  double range = 0.0, width = 0.0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    range += w[i] * (span - 2.0 * r[i]);
    width += w[i] * std::min(2.0 * r[i], span - 2.0 * r[i]);
  }
  const auto m = hs::measure_major_loop(pi_only(r, w), 1e-4, 1.0, 2);
  EXPECT_NEAR(m.range_um, range, 1e-3);
  EXPECT_NEAR(m.width_at_mid_um, width, 1e-3);
  EXPECT_NEAR(m.hysteresis_percent, 100.0 * width / range, 1e-2);
  EXPECT_NEAR(m.max_um - m.min_um, m.range_um, 1e-12);
}

TEST(MajorLoopMetrics, RejectsBadArguments) {
  EXPECT_THROW(hs::measure_major_loop({}, 1e-3, 0.0), std::invalid_argument);
  EXPECT_THROW(hs::measure_major_loop({}, 1e-3, 1.0, 1), std::invalid_argument);
  EXPECT_THROW(hs::measure_major_loop({}, -1.0), std::invalid_argument);
}
