#pragma once
// The simulated actuator with every effect of its default truth on: rate dependence, delay,
// a random-walk thermal drift and the mechanical stops beside the defaults (the heaviest tick).
#include "hystbench/sim/simulated_actuator_config.hpp"

namespace hystbench::testing {

inline sim::SimulatedActuatorConfig every_effect_on() {
  sim::SimulatedActuatorConfig c;
  c.rate_dependence.enabled = true;
  c.delay.enabled = true;
  c.thermal_drift.enabled = true;
  c.thermal_drift.shape = sim::DriftShape::kRandomWalk;
  c.displacement_saturation.enabled = true;
  return c;
}

}  // namespace hystbench::testing
