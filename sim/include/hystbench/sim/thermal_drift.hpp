#pragma once
// Slow thermal drift of the output offset [µm]: a sinusoid of long period, or a seeded Gaussian
// random walk clamped to +-limit. step() is real-time safe; the constructor does not allocate.
#include <random>

#include "hystbench/sim/simulated_actuator_config.hpp"

namespace hystbench::sim {

class ThermalDrift {
 public:
  /// The config is taken as given (validate() first); disabled gives a constant 0.
  ThermalDrift(const SimulatedActuatorConfig::ThermalDrift& config, double dt_s);

  /// Advances one sample period; returns the offset at the new time [µm].
  double step() noexcept;
  /// Offset 0 at time 0, random walk restarted from its seed.
  void reset() noexcept;

 private:
  SimulatedActuatorConfig::ThermalDrift config_;
  double dt_s_;
  long long samples_ = 0;
  double walk_um_ = 0.0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> unit_normal_{0.0, 1.0};
};

}  // namespace hystbench::sim
