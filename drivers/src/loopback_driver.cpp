#include "hystbench/drivers/loopback_driver.hpp"

#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string>

#include "hystbench/sim/simulated_actuator.hpp"
#include "hystbench/sim/simulated_stage.hpp"

namespace hystbench::drivers {

namespace {
bool armed(const std::atomic<std::uint64_t>& at, std::uint64_t tick) noexcept {
  const std::uint64_t v = at.load(std::memory_order_relaxed);
  return v != 0 && tick >= v;
}

/// The [driver.loopback.stage] table; its axes must share the first one's input range.
Result stage_config(const nlohmann::json& j, std::optional<sim::SimulatedStageConfig>& out) {
  try {
    out = sim::stage_from_json(j);
  } catch (const std::invalid_argument& e) {
    return Result::failure(std::string("driver.loopback.stage.") + e.what());
  }
  const auto& first = out->axes.front().actuator.input;
  for (std::size_t i = 1; i < out->axes.size(); ++i) {
    const auto& in = out->axes[i].actuator.input;
    if (in.min_v != first.min_v || in.max_v != first.max_v) {
      return Result::failure("driver.loopback.stage.axes[" + std::to_string(i) +
                             "].actuator.input: the loopback's axes share one input range, "
                             "axis 0's");
    }
  }
  return Result::success();
}

/// The [driver.loopback.faults] table.
Result fault_injection(const nlohmann::json& f, FaultInjection& out) {
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
  out.read_error_at_tick = f.value("read_error_at_tick", std::uint64_t{0});
  out.nan_at_tick = f.value("nan_at_tick", std::uint64_t{0});
  out.stuck_at_tick = f.value("stuck_at_tick", std::uint64_t{0});
  out.write_error_at_tick = f.value("write_error_at_tick", std::uint64_t{0});
  return Result::success();
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
    if (key != "actuator" && key != "stage" && key != "safe_output_v" && key != "max_rate_hz" &&
        key != "faults") {
      return Result::failure("driver.loopback." + key +
                             ": unknown key (actuator, stage, safe_output_v, max_rate_hz, faults)");
    }
  }
  if (p.contains("actuator") && p.contains("stage")) {
    return Result::failure(
        "driver.loopback.stage: a stage has an actuator per axis (its axes' \"actuator\" "
        "tables); give \"actuator\" or \"stage\", not both");
  }
  actuator_.reset();
  stage_.reset();
  try {
    sim::SimulatedActuatorConfig cfg;
    std::optional<sim::SimulatedStageConfig> stage;
    if (p.contains("stage")) {
      if (Result r = stage_config(p["stage"], stage); !r) return r;
      cfg = stage->axes.front().actuator;
    } else {
      cfg = sim::from_json(p.value("actuator", nlohmann::json::object()));
    }
    max_rate_hz_ = p.value("max_rate_hz", 20000.0);
    if (!(max_rate_hz_ > 0.0)) return Result::failure("driver.loopback.max_rate_hz: must be > 0");
    safe_output_v_ = p.value("safe_output_v", cfg.input.min_v);
    if (!(safe_output_v_ >= cfg.input.min_v && safe_output_v_ <= cfg.input.max_v)) {
      return Result::failure(
          "driver.loopback.safe_output_v: must be within the actuator input "
          "range");
    }
    if (stage) {
      stage_ = std::make_unique<sim::SimulatedStage>(*stage, 1.0 / rate_hz);
    } else {
      actuator_ = std::make_unique<sim::SimulatedActuator>(cfg, 1.0 / rate_hz);
    }
    if (p.contains("faults")) {
      FaultInjection fi;
      if (Result r = fault_injection(p["faults"], fi); !r) return r;
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
  outputs_v_.fill(safe_output_v_);
  if (stage_) {
    stage_->reset(std::span<const double>(outputs_v_).first(stage_->axes()));
  } else {
    actuator_->reset(safe_output_v_);
  }
  tick_.store(0, std::memory_order_relaxed);
  return Result::success();
}

std::size_t LoopbackDriver::axes() const noexcept { return stage_ ? stage_->axes() : 1; }

const sim::SimulatedActuator* LoopbackDriver::actuator() const noexcept {
  return stage_ ? &stage_->axis(0) : actuator_.get();
}

DriverStatus LoopbackDriver::write(double output_v) noexcept {
  if (armed(write_error_at_, tick_.load(std::memory_order_relaxed) + 1)) {
    return DriverStatus::kError;
  }
  outputs_v_[0] = output_v;
  return DriverStatus::kOk;
}

DriverStatus LoopbackDriver::write_axes(std::span<const double> outputs_v) noexcept {
  if (armed(write_error_at_, tick_.load(std::memory_order_relaxed) + 1)) {
    return DriverStatus::kError;
  }
  for (std::size_t i = 0; i < outputs_v.size() && i < axes(); ++i) outputs_v_[i] = outputs_v[i];
  return DriverStatus::kOk;
}

DriverStatus LoopbackDriver::advance() noexcept {
  const std::uint64_t tick = tick_.fetch_add(1, std::memory_order_relaxed) + 1;
  // The plant advances whatever the sensor does.
  if (stage_) {
    stage_->step(std::span<const double>(outputs_v_).first(axes()),
                 std::span<double>(y_).first(axes()));
  } else {
    y_[0] = actuator_->step(outputs_v_[0]);
  }
  if (armed(read_error_at_, tick)) return DriverStatus::kError;
  reading_nan_ = armed(nan_at_, tick);
  if (!reading_nan_ && !armed(stuck_at_, tick)) last_y_ = y_;
  return DriverStatus::kOk;
}

DriverStatus LoopbackDriver::read(Measurement& out) noexcept {
  const DriverStatus s = advance();
  out.age_ticks = 0;
  if (s != DriverStatus::kOk) return s;
  out.position_um = reading_nan_ ? std::numeric_limits<double>::quiet_NaN() : last_y_[0];
  return s;
}

DriverStatus LoopbackDriver::read_axes(std::span<Measurement> out) noexcept {
  const DriverStatus s = advance();
  for (std::size_t i = 0; i < out.size() && i < axes(); ++i) {
    out[i].age_ticks = 0;
    if (s != DriverStatus::kOk) continue;
    out[i].position_um = reading_nan_ ? std::numeric_limits<double>::quiet_NaN() : last_y_[i];
  }
  return s;
}

DriverStatus LoopbackDriver::safe_state() noexcept {
  outputs_v_.fill(safe_output_v_);
  return DriverStatus::kOk;
}

DriverInfo LoopbackDriver::info() const noexcept {
  DriverInfo i;
  i.max_rate_hz = max_rate_hz_;
  i.safe_output_v = safe_output_v_;
  const sim::SimulatedActuator* a = actuator();
  if (!a) return i;
  i.output_min_v = a->input_min();
  i.output_max_v = a->input_max();
  const auto& adc = a->config().adc;
  if (adc.enabled)
    i.measurement_resolution_um =
        (adc.range_max - adc.range_min) / (std::ldexp(1.0, adc.bits) - 1.0);
  return i;
}

nlohmann::json LoopbackDriver::diagnostics() const {
  nlohmann::json d = {{"type", "loopback"},
                      {"ticks", tick_.load(std::memory_order_relaxed)},
                      {"output_v", outputs_v_[0]}};
  if (stage_) {
    nlohmann::json axes = nlohmann::json::array();
    for (std::size_t i = 0; i < stage_->axes(); ++i) {
      axes.push_back({{"name", std::string(stage_->axis_name(i))}, {"output_v", outputs_v_[i]}});
    }
    d["axes"] = axes;
  }
  return d;
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
