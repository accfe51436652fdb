#pragma once
// Loopback driver: the simulated actuator in place of hardware, for CI and offline work.
// write() holds the output for the tick, read() advances the simulation by one sample with it.
// Params (JSON): {"actuator": {...SimulatedActuatorConfig...}, "safe_output_v": 0,
//                 "max_rate_hz": 20000, "faults": {...FaultInjection...}}
// Real-time safe write()/read()/safe_state().
#include <atomic>
#include <memory>
#include <optional>

#include "hystbench/drivers/driver.hpp"

namespace hystbench::sim {
class SimulatedActuator;
}

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

  /// Output range: the actuator's input range; measurement_resolution_um: the simulated ADC's
  /// step (range / (2^bits - 1)), 0 with the ADC off.
  DriverInfo info() const noexcept override;
  std::string_view type() const noexcept override { return "loopback"; }
  nlohmann::json diagnostics() const override;

  /// Arms faults relative to the current tick (thread-safe; takes effect on the next tick).
  void inject(const FaultInjection& faults) noexcept;
  /// The simulated actuator (for tests that compare against the truth).
  const sim::SimulatedActuator* actuator() const noexcept { return actuator_.get(); }

 private:
  std::unique_ptr<sim::SimulatedActuator> actuator_;
  double safe_output_v_ = 0.0;
  double max_rate_hz_ = 20000.0;
  double output_v_ = 0.0;
  double last_position_ = 0.0;
  std::atomic<std::uint64_t> tick_{0};  // read by inject()/diagnostics() from other threads
  std::atomic<std::uint64_t> read_error_at_{0}, nan_at_{0}, stuck_at_{0}, write_error_at_{0};
};

}  // namespace hystbench::drivers
