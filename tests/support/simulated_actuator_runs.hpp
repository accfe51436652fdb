#pragma once
// Runs of the simulated actuator for its tests: the configuration with every effect off (a
// perfect linear actuator), a run's measured and true positions [µm] over an input [V], and a
// ramp of inputs.
#include <cstddef>
#include <vector>

#include "hystbench/sim/simulated_actuator.hpp"

namespace hystbench::testing {

/// A perfect linear actuator: every effect off (the hysteresis becomes its linear equivalent).
inline sim::SimulatedActuatorConfig every_effect_off() {
  sim::SimulatedActuatorConfig c;
  c.hysteresis.enabled = false;
  c.rate_dependence.enabled = false;
  c.creep.enabled = false;
  c.dynamics.enabled = false;
  c.sensor_filter.enabled = false;
  c.delay.enabled = false;
  c.sensor_noise.enabled = false;
  c.dac.enabled = false;
  c.adc.enabled = false;
  c.thermal_drift.enabled = false;
  c.input_saturation.enabled = false;
  c.displacement_saturation.enabled = false;
  return c;
}

struct Run {
  std::vector<double> measured;  ///< what the sensor reads [µm]
  std::vector<double> truth;     ///< the true position [µm]
};

/// Steps the actuator through u, from the state it is in.
inline Run run(sim::SimulatedActuator& actuator, const std::vector<double>& u) {
  Run r;
  for (const double v : u) {
    r.measured.push_back(actuator.step(v));
    r.truth.push_back(actuator.true_position());
  }
  return r;
}

/// n steps at the input u.
inline Run run_held(sim::SimulatedActuator& actuator, double u, std::size_t n) {
  return run(actuator, std::vector<double>(n, u));
}

/// n inputs from `from` to `to`, both included.
inline std::vector<double> ramp(double from, double to, std::size_t n) {
  std::vector<double> u(n);
  for (std::size_t k = 0; k < n; ++k) u[k] = from + (to - from) * k / (n - 1.0);
  return u;
}

}  // namespace hystbench::testing
