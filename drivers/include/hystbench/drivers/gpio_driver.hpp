#pragma once
// A driver with GPIO lines: wraps any driver and adds the lines of its `gpio` table (see
// gpio_lines.hpp) without the loop knowing. Without a `gpio` table it only forwards.
//   write()/read(): the e-stop is sampled in both; asserted (or unreadable) = the inner driver's
//     safe_state() and the enable line off in the same call, and kFault (diagnostics say
//     "e-stop asserted"). The fault clears when the e-stop is released (then `reset`).
//   set_run_active(): enable and run_active follow the run; the sync pulse starts.
//   safe_state(), deactivate(), on_error(): the outputs off, then the inner driver's.
// Real-time: one line read per write()/read(), line writes only on run changes and pulses.
#include <atomic>
#include <memory>

#include "hystbench/drivers/driver.hpp"
#include "hystbench/drivers/gpio_lines.hpp"

namespace hystbench::drivers {

class GpioDriver final : public Driver {
 public:
  /// `backend` null = libgpiod.
  explicit GpioDriver(std::unique_ptr<Driver> inner, std::shared_ptr<GpioBackend> backend = {});
  ~GpioDriver() override;

  /// Takes the `gpio` key out of `params` for the lines, passes the rest to the inner driver.
  Result configure(const nlohmann::json& params, double rate_hz) override;
  /// Requests the lines, then activates the inner driver.
  Result activate() override;
  Result deactivate() override;
  Result on_error() override;

  DriverStatus write(double output_v) noexcept override;
  DriverStatus read(Measurement& out) noexcept override;
  DriverStatus safe_state() noexcept override;
  void set_run_active(bool active) noexcept override;

  double max_rate_hz() const noexcept override { return inner_->max_rate_hz(); }
  double output_min_v() const noexcept override { return inner_->output_min_v(); }
  double output_max_v() const noexcept override { return inner_->output_max_v(); }
  double safe_output_v() const noexcept override { return inner_->safe_output_v(); }
  double measurement_resolution_um() const noexcept override {
    return inner_->measurement_resolution_um();
  }
  std::string_view type() const noexcept override { return inner_->type(); }
  /// The inner driver's, with "gpio": {lines, estop, run_active}.
  nlohmann::json diagnostics() const override;

  Driver& inner() noexcept { return *inner_; }

 private:
  bool estop() noexcept;

  std::unique_ptr<Driver> inner_;
  std::shared_ptr<GpioBackend> backend_;
  GpioConfig config_;
  GpioLines lines_;
  std::atomic<bool> estop_asserted_{false};
  std::atomic<std::uint64_t> estop_trips_{0};
  std::atomic<bool> run_active_{false};
};

/// `inner` wrapped in a GpioDriver (for the backend table).
template <typename D>
std::unique_ptr<Driver> with_gpio() {
  return std::make_unique<GpioDriver>(std::make_unique<D>());
}

}  // namespace hystbench::drivers
