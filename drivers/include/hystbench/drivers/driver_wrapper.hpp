#pragma once
// A driver that holds another and forwards every hook to it: the base of the wrappers
// (GpioDriver, IoThreadDriver), which override what they add. Forwarding adds one virtual call;
// real-time safety is the wrapped driver's.
#include <memory>

#include "hystbench/drivers/driver_interface.hpp"

namespace hystbench::drivers {

class DriverWrapper : public DriverInterface {
 public:
  explicit DriverWrapper(std::unique_ptr<DriverInterface> inner) : inner_(std::move(inner)) {}

  Result on_configure(const nlohmann::json& params, double rate_hz) override {
    return inner_->on_configure(params, rate_hz);
  }
  Result on_activate() override { return inner_->on_activate(); }
  Result on_deactivate() override { return inner_->on_deactivate(); }
  DriverStatus on_error() noexcept override { return inner_->on_error(); }

  DriverStatus write(double output_v) noexcept override { return inner_->write(output_v); }
  DriverStatus read(Measurement& out) noexcept override { return inner_->read(out); }
  DriverStatus safe_state() noexcept override { return inner_->safe_state(); }
  std::size_t axes() const noexcept override { return inner_->axes(); }
  DriverStatus write_axes(std::span<const double> outputs_v) noexcept override {
    return inner_->write_axes(outputs_v);
  }
  DriverStatus read_axes(std::span<Measurement> out) noexcept override {
    return inner_->read_axes(out);
  }
  void set_run_active(bool active) noexcept override { inner_->set_run_active(active); }

  DriverInfo info() const noexcept override { return inner_->info(); }
  double activation_position_um() const noexcept override {
    return inner_->activation_position_um();
  }
  std::string_view type() const noexcept override { return inner_->type(); }
  nlohmann::json diagnostics() const override { return inner_->diagnostics(); }
  /// Both this wrapper's reports and the wrapped driver's go to `log`.
  void attach(FaultLog& log) noexcept override {
    DriverInterface::attach(log);
    inner_->attach(log);
  }

  DriverInterface& inner() noexcept { return *inner_; }

 protected:
  std::unique_ptr<DriverInterface> inner_;
};

}  // namespace hystbench::drivers
