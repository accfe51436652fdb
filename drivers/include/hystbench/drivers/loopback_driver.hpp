#pragma once
// Loopback driver: the simulated actuator in place of hardware, for CI and offline work.
// write() holds the output for the tick, read() advances the simulation by one sample with it.
// Params (JSON): {"actuator": {...SimulatedActuatorConfig...}, "safe_output_v": 0,
//                 "max_rate_hz": 20000, "faults": {...FaultInjection...}}
// or, for a stage of several axes, "stage": {...SimulatedStageConfig...} in place of
// "actuator" (sim::stage_from_json; its axes share one input range): write_axes()/read_axes()
// serve every axis, write()/read() the first while the others hold the safe output. Injected
// faults act on every axis.
// Real-time safe write()/read()/write_axes()/read_axes()/safe_state().
#include <array>
#include <atomic>
#include <memory>
#include <optional>

#include "hystbench/drivers/driver.hpp"

namespace hystbench::sim {
class SimulatedActuator;
class SimulatedStage;
}  // namespace hystbench::sim

namespace hystbench::drivers {

/// Faults the loopback driver can inject, to test the loop's reactions. Ticks count from
/// activate(); 0 = never.
struct FaultInjection {
  std::uint64_t read_error_at_tick = 0;   ///< read() returns kError from this tick on
  std::uint64_t nan_at_tick = 0;          ///< read() returns NaN from this tick on
  std::uint64_t stuck_at_tick = 0;        ///< read() repeats the last value from this tick on
  std::uint64_t write_error_at_tick = 0;  ///< write() returns kError from this tick on
};

class LoopbackDriver final : public DriverInterface {
 public:
  LoopbackDriver();
  ~LoopbackDriver() override;

  Result on_configure(const nlohmann::json& params, double rate_hz) override;
  /// The simulated actuator starts from rest at the safe output.
  Result on_activate() override;

  /// Holds the output for the tick.
  DriverStatus write(double output_v) noexcept override;
  /// Advances the simulation by one sample with the held output.
  DriverStatus read(Measurement& out) noexcept override;
  DriverStatus safe_state() noexcept override;
  std::size_t axes() const noexcept override;
  DriverStatus write_axes(std::span<const double> outputs_v) noexcept override;
  /// Advances the stage by one sample with the held outputs.
  DriverStatus read_axes(std::span<Measurement> out) noexcept override;

  /// Output range: the actuator's input range; measurement_resolution_um: the simulated ADC's
  /// step (range / (2^bits - 1)), 0 with the ADC off.
  DriverInfo info() const noexcept override;
  std::string_view type() const noexcept override { return "loopback"; }
  nlohmann::json diagnostics() const override;

  /// Arms faults relative to the current tick (thread-safe; takes effect on the next tick).
  void inject(const FaultInjection& faults) noexcept;
  /// The simulated actuator, or the stage's first axis (for tests that compare against the
  /// truth).
  const sim::SimulatedActuator* actuator() const noexcept;
  /// The simulated stage; null with "actuator".
  const sim::SimulatedStage* stage() const noexcept { return stage_.get(); }

 private:
  /// One simulated sample with the held outputs into y_ (every axis), with the injected faults;
  /// the tick's status.
  DriverStatus advance() noexcept;

  std::unique_ptr<sim::SimulatedActuator> actuator_;
  std::unique_ptr<sim::SimulatedStage> stage_;
  std::array<double, kMaxAxes> outputs_v_{};  // held per axis (one without a stage)
  std::array<double, kMaxAxes> y_{};          // the last sample's readings, per axis
  std::array<double, kMaxAxes> last_y_{};     // what read() reports (stuck holds it)
  double safe_output_v_ = 0.0;
  double max_rate_hz_ = 20000.0;
  bool reading_nan_ = false;            // this tick's injected NaN
  std::atomic<std::uint64_t> tick_{0};  // read by inject()/diagnostics() from other threads
  std::atomic<std::uint64_t> read_error_at_{0}, nan_at_{0}, stuck_at_{0}, write_error_at_{0};
};

}  // namespace hystbench::drivers
