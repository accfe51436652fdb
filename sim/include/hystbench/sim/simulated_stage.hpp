#pragma once
// A simulated stage of several axes, each a SimulatedActuator, coupled between their modes and
// their sensors. Per sample, for every axis i:
//   s_i = stroke_i(u_i)                                (clamp, DAC, delay, hysteresis, creep)
//   x_i = modes_i(s_i) + sum_{j != i} gains[i][j] shared(s_j)   (shared: the shared mode)
//   y_i = measure_i(x_i)                               (drift, clamp, sensor, noise, ADC)
// With one axis, or the coupling off, every axis is exactly its SimulatedActuator.
// Units: V in, µm out. Construction allocates and throws; step(), reset() and the accessors are
// real-time safe (no allocation, no exceptions; O(axes^2) beyond the actuators' own work).
#include <cstddef>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "hystbench/compensation/second_order_dynamics.hpp"
#include "hystbench/sim/simulated_actuator.hpp"
#include "hystbench/sim/simulated_stage_config.hpp"

namespace hystbench::sim {

class SimulatedStage {
 public:
  /// Validates the config and dt_s (> 0) [s]; throws std::invalid_argument naming the field.
  /// Starts relaxed at every axis's input_min(), as after reset().
  SimulatedStage(const SimulatedStageConfig& config, double dt_s);

  std::size_t axes() const noexcept { return axes_.size(); }
  std::string_view axis_name(std::size_t i) const noexcept { return config_.axes[i].name; }
  /// Axis i's actuator (its true_position(), applied_input() and ranges).
  const SimulatedActuator& axis(std::size_t i) const noexcept { return *axes_[i]; }
  const SimulatedStageConfig& config() const noexcept { return config_; }

  /// Applies u_volts[i] [V] to axis i for one sample period and writes the measured
  /// displacements [µm] to y_um[i]. An axis without an input (u_volts shorter than axes()) or
  /// with a non-finite one holds its previous input; y_um's extra axes are not written.
  void step(std::span<const double> u_volts, std::span<double> y_um) noexcept;
  /// Every axis relaxed and settled at u0[i] [V] (input_min() where u0 has none), the coupling
  /// settled with them, every noise generator back to its seed: a run after reset() repeats.
  void reset(std::span<const double> u0 = {}) noexcept;

 private:
  bool coupled() const noexcept { return !shared_.empty(); }
  /// The coupling's contribution to axis i from the shared mode's outputs [µm].
  double cross(std::size_t i) const noexcept;

  SimulatedStageConfig config_;
  std::vector<std::unique_ptr<SimulatedActuator>> axes_;
  std::vector<compensation::SecondOrderDynamics> shared_;  // one per source axis j
  std::vector<double> shared_out_;                         // shared_[j]'s last output [µm]
  std::vector<double> strokes_;                            // this sample's strokes [µm]
};

}  // namespace hystbench::sim
