#pragma once
// A virtual piezo actuator for running the bench without hardware. Signal path per sample:
//   u -> input clamp -> DAC -> truth (delay -> hysteresis + creep -> dynamics) + drift
//     -> displacement clamp = true_position() -> + sensor noise -> ADC = step()'s return.
// The truth is a compensation::ActuatorModel built from the config, so identified models can
// be compared with it directly. Units: V in, µm out.
// Construction allocates and throws; step(), reset() and the accessors are real-time safe
// (no allocation, no exceptions, O(number of operators)).
#include <cstdint>
#include <random>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/sim/quantizer.hpp"
#include "hystbench/sim/simulated_actuator_config.hpp"
#include "hystbench/sim/thermal_drift.hpp"

namespace hystbench::sim {

class SimulatedActuator {
 public:
  /// Validates the config and dt_s (> 0) [s]; throws std::invalid_argument naming the field.
  /// Starts relaxed at input_min(), as after reset(input_min()).
  SimulatedActuator(const SimulatedActuatorConfig& config, double dt_s);

  /// Applies u_volts [V] for one sample period and returns the measured displacement [µm]
  /// (noise and ADC included). A non-finite u_volts holds the previous applied input.
  double step(double u_volts) noexcept;
  /// Every part relaxed and settled at input u0 [V] (clamped and quantised like step()'s
  /// input), drift back to 0 and both noise generators back to their seeds: a run after
  /// reset() repeats exactly.
  void reset(double u0) noexcept;

  /// Noise-free displacement after the last step() [µm] (drift and displacement clamp included).
  double true_position() const noexcept { return true_position_; }
  /// Voltage the stack saw on the last step(), after clamp and DAC [V].
  double applied_input() const noexcept { return applied_input_; }
  const SimulatedActuatorConfig& config() const noexcept { return config_; }
  /// Amplifier input range [V].
  double input_min() const noexcept { return config_.input.min_v; }
  double input_max() const noexcept { return config_.input.max_v; }
  double sample_period() const noexcept { return dt_s_; }
  /// The deterministic truth (hysteresis, creep, dynamics, delay), in its current state.
  const compensation::ActuatorModel& truth_model() const noexcept { return truth_; }

 private:
  double condition_input(double u_volts) const noexcept;
  double clamp_displacement(double x_um) const noexcept;

  SimulatedActuatorConfig config_;
  double dt_s_;
  compensation::ActuatorModel truth_;
  Quantizer dac_;
  Quantizer adc_;
  ThermalDrift drift_;
  std::mt19937_64 noise_rng_;
  std::normal_distribution<double> unit_normal_{0.0, 1.0};
  double applied_input_ = 0.0;
  double true_position_ = 0.0;
};

/// The deterministic part of the simulated actuator as a model (what an identification of a
/// noise-free record should find): hysteresis, creep, dynamics and delay of the enabled
/// effects; input_min/input_max from config.input. Validates like the constructor.
compensation::ActuatorModel make_truth_model(const SimulatedActuatorConfig& config, double dt_s);

}  // namespace hystbench::sim
