#pragma once
// A record (t, u, y) of the simulated actuator driven by the identification excitation over
// 0..150 V: the measured data the offline-command tests hand to fit, simulate and diagnose.
#include <cstdint>
#include <vector>

#include "hystbench/sim/identification_excitation.hpp"
#include "hystbench/sim/simulated_actuator.hpp"

namespace hystbench::test {

struct SimulatedRecord {
  std::vector<double> t, u, y;  ///< [s], [V], [µm]
};

/// Runs `config` (sensor-noise seed replaced by `noise_seed`) at sample period dt_s [s] over
/// identification_excitation(0, 150, dt_s, options), starting relaxed at the first input.
inline SimulatedRecord simulate_record(const sim::SimulatedActuatorConfig& config, double dt_s,
                                       const sim::IdentificationExcitationOptions& options,
                                       std::uint64_t noise_seed) {
  sim::SimulatedActuatorConfig c = config;
  c.sensor_noise.seed = noise_seed;
  sim::SimulatedActuator actuator(c, dt_s);
  const sim::Excitation x = sim::identification_excitation(0.0, 150.0, dt_s, options);
  SimulatedRecord r;
  actuator.reset(x.samples.front());
  for (std::size_t k = 0; k < x.samples.size(); ++k) {
    r.t.push_back(static_cast<double>(k) * dt_s);
    r.u.push_back(x.samples[k]);
    r.y.push_back(actuator.step(x.samples[k]));
  }
  return r;
}

}  // namespace hystbench::test
