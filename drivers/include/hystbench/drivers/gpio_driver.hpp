#pragma once
// A driver with GPIO lines: wraps any driver and adds the lines of its `gpio` table (see
// gpio_lines.hpp) without the loop knowing. Without a `gpio` table it only forwards.
//   write()/read(): the e-stop is sampled in both; asserted (or unreadable) = the inner driver's
//     safe_state() and the enable line off in the same call, and kFault (the fault in words:
//     "e-stop asserted"). The fault clears when the e-stop is released (then `reset`).
//   set_run_active(): enable and run_active follow the run; the sync pulse starts.
//   safe_state(), on_deactivate(), on_error(): the outputs off, then the inner driver's.
// Real-time: one line read per write()/read(), line writes only on run changes and pulses.
#include <atomic>
#include <memory>

#include "hystbench/drivers/driver_wrapper.hpp"
#include "hystbench/drivers/gpio_lines.hpp"

namespace hystbench::drivers {

class GpioDriver final : public DriverWrapper {
 public:
  enum class Fault : int { kNone = 0, kEstop };

  /// `backend` null = libgpiod.
  explicit GpioDriver(std::unique_ptr<DriverInterface> inner,
                      std::shared_ptr<GpioBackend> backend = {});
  ~GpioDriver() override;

  /// Takes the `gpio` key out of `params` for the lines, passes the rest to the inner driver.
  Result on_configure(const nlohmann::json& params, double rate_hz) override;
  /// Requests the lines, then activates the inner driver.
  Result on_activate() override;
  Result on_deactivate() override;
  DriverStatus on_error() noexcept override;

  DriverStatus write(double output_v) noexcept override;
  /// As write()/read(), for every axis of the wrapped driver.
  DriverStatus write_axes(std::span<const double> outputs_v) noexcept override;
  DriverStatus read_axes(std::span<Measurement> out) noexcept override;
  DriverStatus read(Measurement& out) noexcept override;
  DriverStatus safe_state() noexcept override;
  void set_run_active(bool active) noexcept override;

  /// The inner driver's, with "gpio": {lines, estop_asserted, estop_trips, run_active}.
  nlohmann::json diagnostics() const override;
  std::string describe_fault(int cause, std::int64_t detail) const override;

 private:
  bool estop() noexcept;

  std::shared_ptr<GpioBackend> backend_;
  GpioConfig config_;
  GpioLines lines_;
  std::atomic<bool> estop_asserted_{false};
  std::atomic<std::uint64_t> estop_trips_{0};
  std::atomic<bool> run_active_{false};
};

}  // namespace hystbench::drivers
