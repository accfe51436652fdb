#include "hystbench/drivers/loopback_driver.hpp"

#include <cmath>
#include <limits>

#include "hystbench/sim/simulated_actuator.hpp"

namespace hystbench::drivers {

namespace {
bool armed(const std::atomic<std::uint64_t>& at, std::uint64_t tick) noexcept {
  const std::uint64_t v = at.load(std::memory_order_relaxed);
  return v != 0 && tick >= v;
}
}  // namespace

LoopbackDriver::LoopbackDriver() = default;
LoopbackDriver::~LoopbackDriver() = default;

Result LoopbackDriver::on_configure(const nlohmann::json& params, double rate_hz) {
  if (!params.is_null() && !params.is_object()) {
    return Result::failure("driver.loopback: must be a table");
  }
  const nlohmann::json p = params.is_null() ? nlohmann::json::object() : params;
  for (const auto& [key, value] : p.items()) {
    if (key != "actuator" && key != "safe_output_v" && key != "max_rate_hz" && key != "faults") {
      return Result::failure("driver.loopback." + key +
                             ": unknown key (actuator, safe_output_v, max_rate_hz, faults)");
    }
  }
  try {
    const sim::SimulatedActuatorConfig cfg =
        sim::from_json(p.value("actuator", nlohmann::json::object()));
    max_rate_hz_ = p.value("max_rate_hz", 20000.0);
    if (!(max_rate_hz_ > 0.0)) return Result::failure("driver.loopback.max_rate_hz: must be > 0");
    safe_output_v_ = p.value("safe_output_v", cfg.input.min_v);
    if (!(safe_output_v_ >= cfg.input.min_v && safe_output_v_ <= cfg.input.max_v)) {
      return Result::failure(
          "driver.loopback.safe_output_v: must be within the actuator input "
          "range");
    }
    actuator_ = std::make_unique<sim::SimulatedActuator>(cfg, 1.0 / rate_hz);
    if (p.contains("faults")) {
      const auto& f = p["faults"];
      if (!f.is_object()) return Result::failure("driver.loopback.faults: must be a table");
      // A misspelt fault would silently never fire: the test it was meant for would pass.
      for (const auto& [key, value] : f.items()) {
        if (key != "read_error_at_tick" && key != "nan_at_tick" && key != "stuck_at_tick" &&
            key != "write_error_at_tick") {
          return Result::failure("driver.loopback.faults." + key +
                                 ": unknown key (read_error_at_tick, nan_at_tick, stuck_at_tick, "
                                 "write_error_at_tick)");
        }
        if (!value.is_number_integer() || value.get<long long>() < 0) {
          return Result::failure("driver.loopback.faults." + key +
                                 ": must be a tick number >= 0 (0 = never)");
        }
      }
      FaultInjection fi;
      fi.read_error_at_tick = f.value("read_error_at_tick", std::uint64_t{0});
      fi.nan_at_tick = f.value("nan_at_tick", std::uint64_t{0});
      fi.stuck_at_tick = f.value("stuck_at_tick", std::uint64_t{0});
      fi.write_error_at_tick = f.value("write_error_at_tick", std::uint64_t{0});
      read_error_at_ = fi.read_error_at_tick;
      nan_at_ = fi.nan_at_tick;
      stuck_at_ = fi.stuck_at_tick;
      write_error_at_ = fi.write_error_at_tick;
    }
  } catch (const std::exception& e) {
    return Result::failure(std::string("driver.loopback: ") + e.what());
  }
  return Result::success();
}

Result LoopbackDriver::on_activate() {
  actuator_->reset(safe_output_v_);
  output_v_ = safe_output_v_;
  tick_.store(0, std::memory_order_relaxed);
  return Result::success();
}

DriverStatus LoopbackDriver::write(double output_v) noexcept {
  if (armed(write_error_at_, tick_.load(std::memory_order_relaxed) + 1)) {
    return DriverStatus::kError;
  }
  output_v_ = output_v;
  return DriverStatus::kOk;
}

DriverStatus LoopbackDriver::read(Measurement& out) noexcept {
  const std::uint64_t tick = tick_.fetch_add(1, std::memory_order_relaxed) + 1;
  const double y = actuator_->step(output_v_);  // the plant advances whatever the sensor does
  out.age_ticks = 0;
  if (armed(read_error_at_, tick)) return DriverStatus::kError;
  if (armed(nan_at_, tick)) {
    out.position_um = std::numeric_limits<double>::quiet_NaN();
    return DriverStatus::kOk;
  }
  if (!armed(stuck_at_, tick)) last_position_ = y;
  out.position_um = last_position_;
  return DriverStatus::kOk;
}

DriverStatus LoopbackDriver::safe_state() noexcept {
  output_v_ = safe_output_v_;
  return DriverStatus::kOk;
}

DriverInfo LoopbackDriver::info() const noexcept {
  DriverInfo i;
  i.max_rate_hz = max_rate_hz_;
  i.safe_output_v = safe_output_v_;
  if (!actuator_) return i;
  i.output_min_v = actuator_->input_min();
  i.output_max_v = actuator_->input_max();
  const auto& adc = actuator_->config().adc;
  if (adc.enabled)
    i.measurement_resolution_um =
        (adc.range_max - adc.range_min) / (std::ldexp(1.0, adc.bits) - 1.0);
  return i;
}

nlohmann::json LoopbackDriver::diagnostics() const {
  return {{"type", "loopback"},
          {"ticks", tick_.load(std::memory_order_relaxed)},
          {"output_v", output_v_}};
}

void LoopbackDriver::inject(const FaultInjection& f) noexcept {
  const std::uint64_t now = tick_.load(std::memory_order_relaxed);
  auto rel = [now](std::uint64_t at) { return at == 0 ? 0 : now + at; };
  read_error_at_ = rel(f.read_error_at_tick);
  nan_at_ = rel(f.nan_at_tick);
  stuck_at_ = rel(f.stuck_at_tick);
  write_error_at_ = rel(f.write_error_at_tick);
}

}  // namespace hystbench::drivers
