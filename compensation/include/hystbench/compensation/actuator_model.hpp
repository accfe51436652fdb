#pragma once
// A complete actuator model: delay -> (hysteresis + creep) -> second-order dynamics.
//   y(k) = D[ H[u(k - n_d)] + C[u(k - n_d)] ]
// n_d need not be whole: a fraction of a sample interpolates the input linearly between the two
// samples around it (DelayLine).
// Every part but the hysteresis is optional. This is what model files hold, what the simulator
// and the diagnosis extend, and what inverses are built from.
// configure() allocates; step()/peek()/reset() are real-time safe.
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "hystbench/compensation/creep_operator_bank.hpp"
#include "hystbench/compensation/delay_line.hpp"
#include "hystbench/compensation/hysteresis_model.hpp"
#include "hystbench/compensation/second_order_dynamics.hpp"

namespace hystbench::compensation {

struct Units {
  std::string input = "V";
  std::string output = "um";
};

class ActuatorModel {
 public:
  ActuatorModel() = default;
  explicit ActuatorModel(std::unique_ptr<HysteresisModel> hysteresis);
  ActuatorModel(const ActuatorModel& other);
  ActuatorModel& operator=(const ActuatorModel& other);
  ActuatorModel(ActuatorModel&&) noexcept = default;
  ActuatorModel& operator=(ActuatorModel&&) noexcept = default;

  // --- structure (not real-time safe) ---
  void set_creep(std::optional<CreepParameters> creep);
  void set_dynamics(std::optional<DynamicsParameters> dynamics);
  void set_delay(double delay_s);  ///< >= 0 [s]; any fraction of a sample is kept
  /// Sample period for every part that depends on time; allocates the delay line. Resets the
  /// state of creep, dynamics and delay (not of the hysteresis).
  void configure(double dt_s);

  // --- real-time path ---
  double step(double u) noexcept;
  /// Static output for input u now (hysteresis + creep), ignoring delay and dynamics.
  double peek_static(double u) const noexcept;
  /// peek_static() with the rate-dependent terms at `rate` (HysteresisModel::peek_at_rate).
  double peek_static_at_rate(double u, double rate) const noexcept;
  /// The rate at which peek_static_at_rate(u, rate) = y (HysteresisModel::rate_for_output).
  double rate_for_static_output(double u, double y) const noexcept;
  /// Relaxed at input u0, every part settled.
  void reset(double u0) noexcept;
  /// The state `steps` step(u) calls would leave: stepped for the first kHoldStepsS seconds'
  /// worth (the delay, the rate, the hysteresis and the modes settle there), the creep's lags
  /// moved over the rest in closed form and the modes settled at the output that leaves. For a
  /// long stretch of one held output (an idle bench), at the cost of a second's steps.
  /// Real-time safe.
  void hold(double u, std::uint64_t steps) noexcept;
  static constexpr double kHoldStepsS = 1.0;

  // --- inspection ---
  bool valid() const noexcept { return hysteresis_ != nullptr; }
  const HysteresisModel& hysteresis() const { return *hysteresis_; }
  HysteresisModel& hysteresis() { return *hysteresis_; }
  const std::optional<CreepParameters>& creep() const noexcept { return creep_params_; }
  const std::optional<DynamicsParameters>& dynamics() const noexcept { return dyn_params_; }
  double delay_s() const noexcept { return delay_s_; }
  /// The delay in whole samples, rounded to the nearest (delay_s() holds any fraction).
  std::size_t delay_samples() const noexcept {
    return static_cast<std::size_t>(std::lround(delay_s_ / dt_));
  }
  double sample_period() const noexcept { return dt_; }
  /// The input of the last step() (or reset()).
  double last_input() const noexcept { return last_input_; }
  /// True when delay and dynamics are absent (the static map can be inverted sample by sample).
  bool is_static() const noexcept { return delay_s_ == 0.0 && !dyn_params_; }

  Units units;
  /// Input range the model was identified on [input unit]; used to bound inverses.
  double input_min = 0.0;
  double input_max = 0.0;

  /// Simulates a whole input signal from reset(u[0]) at sample period dt_s.
  std::vector<double> simulate(std::span<const double> u, double dt_s);

 private:
  std::unique_ptr<HysteresisModel> hysteresis_;
  std::optional<CreepParameters> creep_params_;
  std::optional<DynamicsParameters> dyn_params_;
  double delay_s_ = 0.0;
  double dt_ = 1e-3;
  double last_input_ = 0.0;
  CreepOperatorBank creep_;
  std::optional<SecondOrderDynamics> dynamics_;
  DelayLine delay_;
};

}  // namespace hystbench::compensation
