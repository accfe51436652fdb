#include "hystbench/drivers/gpio_driver.hpp"

namespace hystbench::drivers {

GpioDriver::GpioDriver(std::unique_ptr<DriverInterface> inner, std::shared_ptr<GpioBackend> backend)
    : DriverWrapper(std::move(inner)),
      backend_(backend ? std::move(backend) : make_libgpiod_backend()) {}

GpioDriver::~GpioDriver() { lines_.release(); }

Result GpioDriver::on_configure(const nlohmann::json& params, double rate_hz) {
  nlohmann::json rest = params;
  config_ = GpioConfig{};
  if (rest.is_object() && rest.contains("gpio")) {
    try {
      config_ = parse_gpio_config(rest["gpio"], "driver." + std::string(inner_->type()) + ".gpio");
    } catch (const std::invalid_argument& e) {
      return Result::failure(e.what());
    }
    rest.erase("gpio");
  }
  Result r = inner_->on_configure(rest, rate_hz);
  const std::size_t lines = config_.enable.size(), axes = inner_->axes();
  if (r && lines > 1 && lines != axes) {
    return Result::failure("driver." + std::string(inner_->type()) +
                           ".gpio.enable: " + std::to_string(lines) + " lines for a driver of " +
                           std::to_string(axes) + (axes == 1 ? " axis" : " axes") +
                           ": give one line (every axis) or one per axis");
  }
  return r;
}

Result GpioDriver::on_activate() {
  try {
    lines_.request(config_, *backend_);
  } catch (const std::exception& e) {
    return Result::failure("driver." + std::string(inner_->type()) + ".gpio: " + e.what());
  }
  if (lines_.estop_asserted()) {
    lines_.release();
    return Result::failure("driver." + std::string(inner_->type()) +
                           ".gpio: the e-stop is asserted (" + config_.estop->describe() +
                           "); release it first");
  }
  Result r = inner_->on_activate();
  if (!r) lines_.release();
  return r;
}

Result GpioDriver::on_deactivate() {
  lines_.safe();
  Result r = inner_->on_deactivate();
  lines_.release();
  return r;
}

DriverStatus GpioDriver::on_error() noexcept {
  lines_.safe();
  return inner_->on_error();
}

bool GpioDriver::estop() noexcept {
  if (!lines_.estop_asserted()) {
    estop_asserted_.store(false, std::memory_order_relaxed);
    return false;
  }
  if (!estop_asserted_.exchange(true, std::memory_order_relaxed)) {
    estop_trips_.fetch_add(1, std::memory_order_relaxed);
  }
  report_fault(Fault::kEstop);
  lines_.safe();
  inner_->safe_state();
  return true;
}

DriverStatus GpioDriver::write(double output_v) noexcept {
  if (estop()) return DriverStatus::kFault;
  lines_.tick();
  return inner_->write(output_v);
}

DriverStatus GpioDriver::read(Measurement& out) noexcept {
  const DriverStatus s = inner_->read(out);
  if (estop()) return DriverStatus::kFault;
  return s;
}

DriverStatus GpioDriver::write_axes(std::span<const double> outputs_v) noexcept {
  if (estop()) return DriverStatus::kFault;
  lines_.tick();
  return inner_->write_axes(outputs_v);
}

DriverStatus GpioDriver::read_axes(std::span<Measurement> out) noexcept {
  const DriverStatus s = inner_->read_axes(out);
  if (estop()) return DriverStatus::kFault;
  return s;
}

DriverStatus GpioDriver::safe_state() noexcept {
  lines_.safe();
  return inner_->safe_state();
}

void GpioDriver::set_run_active(bool active) noexcept {
  run_active_.store(active, std::memory_order_relaxed);
  // A run never starts the amplifier while the e-stop is asserted.
  lines_.set_run_active(active && !estop_asserted_.load(std::memory_order_relaxed));
  inner_->set_run_active(active);
}

nlohmann::json GpioDriver::diagnostics() const {
  nlohmann::json d = inner_->diagnostics();
  if (!config_.any()) return d;
  nlohmann::json lines = nlohmann::json::object();
  const auto words = [](const GpioLineConfig& l) {
    return l.describe() + (l.active_low ? " (active low)" : "");
  };
  const auto add = [&](const char* name, const std::optional<GpioLineConfig>& l) {
    if (l) lines[name] = words(*l);
  };
  if (config_.enable.size() == 1) lines["enable"] = words(config_.enable.front());
  if (config_.enable.size() > 1) {
    lines["enable"] = nlohmann::json::array();
    for (const GpioLineConfig& l : config_.enable) lines["enable"].push_back(words(l));
  }
  add("estop", config_.estop);
  add("run_active", config_.run_active);
  add("sync_pulse", config_.sync_pulse);
  d["gpio"] = {{"lines", lines},
               {"estop_asserted", estop_asserted_.load()},
               {"estop_trips", estop_trips_.load()},
               {"run_active", run_active_.load()}};
  return d;
}

std::string GpioDriver::describe_fault(int cause, std::int64_t detail) const {
  if (static_cast<Fault>(cause) != Fault::kEstop || !config_.estop) {
    return DriverInterface::describe_fault(cause, detail);
  }
  return "e-stop asserted (" + config_.estop->describe() + ")";
}

}  // namespace hystbench::drivers
