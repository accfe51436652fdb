#pragma once
// A virtual piezo actuator for running the bench without hardware. Signal path per sample:
//   u -> input clamp -> DAC -> delay -> static map (hysteresis, its rate dependence)
//     -> + creep -> modes -> + drift -> displacement clamp = true_position()
//     -> sensor low-pass -> + sensor noise -> ADC = step()'s return.
// The default truth is outside every model family the bench fits (docs/simulator.md): Preisach
// hysteresis behind a switching front, logarithmic creep of the displacement, two modes and a
// sensor with its own bandwidth. SimulatedActuatorConfig::modified_pi_truth() is the truth the
// models contain (make_truth_model() returns it as a model). Units: V in, µm out.
// Construction allocates and throws; step(), reset() and the accessors are real-time safe
// (no allocation, no exceptions; O(modes + creep lags + plays) per step).
#include <cstdint>
#include <memory>
#include <optional>
#include <random>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/creep_operator_bank.hpp"
#include "hystbench/compensation/delay_line.hpp"
#include "hystbench/compensation/hysteresis_model.hpp"
#include "hystbench/compensation/second_order_dynamics.hpp"
#include "hystbench/sim/modal_dynamics.hpp"
#include "hystbench/sim/preisach_hysteresis.hpp"
#include "hystbench/sim/quantizer.hpp"
#include "hystbench/sim/rate_widened_play.hpp"
#include "hystbench/sim/simulated_actuator_config.hpp"
#include "hystbench/sim/switching_front.hpp"
#include "hystbench/sim/thermal_drift.hpp"

namespace hystbench::sim {

class SimulatedActuator {
 public:
  /// Validates the config and dt_s (> 0) [s]; throws std::invalid_argument naming the field.
  /// Starts relaxed at input_min(), as after reset(input_min()).
  SimulatedActuator(const SimulatedActuatorConfig& config, double dt_s);
  ~SimulatedActuator();
  SimulatedActuator(const SimulatedActuator&) = delete;
  SimulatedActuator& operator=(const SimulatedActuator&) = delete;

  /// Applies u_volts [V] for one sample period and returns the measured displacement [µm]
  /// (sensor filter, noise and ADC included). A non-finite u_volts holds the previous input.
  double step(double u_volts) noexcept;
  /// Every part relaxed and settled at input u0 [V] (clamped and quantised like step()'s
  /// input), drift back to 0 and both noise generators back to their seeds: a run after
  /// reset() repeats exactly.
  void reset(double u0) noexcept;

  /// The signal path in three parts, for a stage that couples several actuators between their
  /// modes and their sensors (SimulatedStage); step(u) is measure(structure(stroke(u))).
  /// stroke: input conditioning, delay, static map and creep: the displacement before the
  /// modes [µm]. structure: the modes. measure: + drift, displacement clamp (true_position()),
  /// sensor filter, noise and ADC: the measured displacement [µm].
  double stroke(double u_volts) noexcept;
  double structure(double x_um) noexcept { return modes_.step(x_um); }
  double measure(double x_um) noexcept;
  /// The stroke after the last stroke() or reset() [µm].
  double last_stroke() const noexcept { return stroke_um_; }
  /// After reset(): the structure's output is x_um instead of the stroke at rest (a stage adds
  /// its coupling); the true position and the sensor settle there.
  void settle_measurement(double x_um) noexcept;

  /// Noise-free displacement after the last step() [µm] (drift and displacement clamp included,
  /// before the sensor's filter).
  double true_position() const noexcept { return true_position_; }
  /// Voltage the stack saw on the last step(), after clamp and DAC [V].
  double applied_input() const noexcept { return applied_input_; }
  const SimulatedActuatorConfig& config() const noexcept { return config_; }
  /// Amplifier input range [V].
  double input_min() const noexcept { return config_.input.min_v; }
  double input_max() const noexcept { return config_.input.max_v; }
  double sample_period() const noexcept { return dt_s_; }

 private:
  double condition_input(double u_volts) const noexcept;
  double clamp_displacement(double x_um) const noexcept;
  /// The static map's output for the delayed input ud (hysteresis and its rate dependence).
  double static_map(double ud) noexcept;

  SimulatedActuatorConfig config_;
  double dt_s_;
  compensation::DelayLine delay_;
  std::optional<PreisachHysteresis> preisach_;
  std::optional<SwitchingFront> front_;
  std::optional<RateWidenedPlay> widened_;                // switching_thresholds
  std::unique_ptr<compensation::HysteresisModel> model_;  // modified PI or linear map
  compensation::CreepOperatorBank input_creep_;           // law input_lags
  compensation::CreepOperatorBank displacement_creep_;    // law logarithmic
  double creep_reference_um_ = 0.0;                       // the static map at input.min_v, relaxed
  ModalDynamics modes_;
  std::optional<compensation::SecondOrderDynamics> sensor_;
  Quantizer dac_;
  Quantizer adc_;
  ThermalDrift drift_;
  std::mt19937_64 noise_rng_;
  std::normal_distribution<double> unit_normal_{0.0, 1.0};
  double applied_input_ = 0.0;
  double stroke_um_ = 0.0;
  double true_position_ = 0.0;
};

/// The deterministic part of a simulated actuator as a model: hysteresis, creep, dynamics and
/// delay of the enabled effects, input_min/input_max from config.input. Only a truth that a model
/// can be (hysteresis.kind modified_pi or hysteresis off, creep law input_lags, one mode, no
/// sensor filter, rate mechanism play_weights: modified_pi_truth()) has one; otherwise throws
/// std::invalid_argument naming what no model contains. Validates like the constructor.
compensation::ActuatorModel make_truth_model(const SimulatedActuatorConfig& config, double dt_s);

}  // namespace hystbench::sim
