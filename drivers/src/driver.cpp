#include "hystbench/drivers/driver.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "hystbench/compensation/number_text.hpp"

namespace hystbench::drivers {

using compensation::fixed;

Driver::Driver(std::unique_ptr<DriverInterface> driver) : driver_(std::move(driver)) {
  driver_->attach(faults_);
}

Driver::~Driver() = default;

template <typename Hook>
Result Driver::guarded(Hook&& hook) const {
  try {
    return hook();
  } catch (const std::exception& e) {
    return Result::failure("driver." + std::string(type()) + ": " + e.what());
  }
}

Result Driver::refuse_rate(const char* when) const {
  if (rate_hz_ <= info_.max_rate_hz) return Result::success();
  return Result::failure("loop.rate_hz: " + fixed(rate_hz_, 0) + " Hz is beyond what the " +
                         std::string(type()) + " driver holds " + when + " (at most " +
                         fixed(info_.max_rate_hz, 0) + " Hz)");
}

Result Driver::configure(const nlohmann::json& params, double rate_hz) {
  if (state() == State::kActive) {
    return Result::failure("driver." + std::string(type()) + ": configure() while active");
  }
  state_.store(State::kUnconfigured, std::memory_order_release);
  if (!(rate_hz > 0.0)) return Result::failure("loop.rate_hz: must be > 0");
  Result r = guarded([&] { return driver_->on_configure(params, rate_hz); });
  if (!r) return r;
  info_ = driver_->info();
  rate_hz_ = rate_hz;
  if (r = refuse_rate("as configured"); !r) return r;
  axes_ = driver_->axes();
  if (axes_ < 1 || axes_ > kMaxAxes) {
    return Result::failure("driver." + std::string(type()) + ": serves " + std::to_string(axes_) +
                           " axes; a driver serves 1 to " + std::to_string(kMaxAxes));
  }
  state_.store(State::kInactive, std::memory_order_release);
  return r;
}

Result Driver::activate() {
  if (state() == State::kActive) return Result::success();
  if (state() == State::kUnconfigured) {
    return Result::failure("driver." + std::string(type()) + ": activate() before configure()");
  }
  faults_.clear();
  Result r = guarded([&] { return driver_->on_activate(); });
  if (!r) return r;
  info_ = driver_->info();
  if (r = refuse_rate("as activated"); !r) {
    driver_->on_deactivate();
    return r;
  }
  in_fault_ = false;
  last_y_.fill(0.0);
  last_y_[0] = driver_->activation_position_um();
  age_ = 0;
  response_ticks_ = 0;
  position_um_.store(last_y_[0]);
  output_v_.store(info_.safe_output_v);
  stale_reads_.store(0);
  state_.store(State::kActive, std::memory_order_release);
  return r;
}

Result Driver::deactivate() {
  if (state() != State::kActive) return Result::success();
  state_.store(State::kInactive, std::memory_order_release);
  output_v_.store(info_.safe_output_v);
  return guarded([&] { return driver_->on_deactivate(); });
}

DriverStatus Driver::faulted(DriverStatus s) noexcept {
  if (s == DriverStatus::kFault && !in_fault_) {
    in_fault_ = true;
    driver_->on_error();
    output_v_.store(info_.safe_output_v, std::memory_order_relaxed);
  }
  return s;
}

DriverStatus Driver::write(double output_v) noexcept {
  if (state_.load(std::memory_order_relaxed) != State::kActive) return DriverStatus::kFault;
  const DriverStatus s = driver_->write(output_v);
  if (s == DriverStatus::kOk) output_v_.store(output_v, std::memory_order_relaxed);
  return faulted(s);
}

DriverStatus Driver::write_axes(std::span<const double> outputs_v) noexcept {
  if (state_.load(std::memory_order_relaxed) != State::kActive) return DriverStatus::kFault;
  const DriverStatus s = driver_->write_axes(outputs_v.first(std::min(outputs_v.size(), axes_)));
  if (s == DriverStatus::kOk && !outputs_v.empty()) {
    output_v_.store(outputs_v.front(), std::memory_order_relaxed);
  }
  return faulted(s);
}

DriverStatus Driver::read(Measurement& out) noexcept {
  if (state_.load(std::memory_order_relaxed) != State::kActive) return DriverStatus::kFault;
  Measurement m;
  const DriverStatus s = driver_->read(m);
  return finish_read(s, std::span<const Measurement>(&m, 1), std::span<Measurement>(&out, 1));
}

DriverStatus Driver::read_axes(std::span<Measurement> out) noexcept {
  if (state_.load(std::memory_order_relaxed) != State::kActive) return DriverStatus::kFault;
  std::array<Measurement, kMaxAxes> m{};
  const std::span<Measurement> fresh = std::span<Measurement>(m).first(axes_);
  const DriverStatus s = driver_->read_axes(fresh);
  return finish_read(s, fresh, out.first(std::min(out.size(), axes_)));
}

DriverStatus Driver::finish_read(DriverStatus s, std::span<const Measurement> fresh,
                                 std::span<Measurement> out) noexcept {
  if (s == DriverStatus::kOk) {
    in_fault_ = false;
    for (std::size_t i = 0; i < fresh.size(); ++i) last_y_[i] = fresh[i].position_um;
    age_ = 0;
    response_ticks_ = fresh.front().response_ticks;
    if (std::isfinite(last_y_[0])) position_um_.store(last_y_[0], std::memory_order_relaxed);
    for (std::size_t i = 0; i < out.size(); ++i) {
      out[i] = {last_y_[i], 0, fresh[i].response_ticks};
    }
    return s;
  }
  ++age_;
  stale_reads_.fetch_add(1, std::memory_order_relaxed);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = {last_y_[i], age_, response_ticks_ + age_};
  if (s == DriverStatus::kStale && info_.max_stale_reads > 0 && age_ >= info_.max_stale_reads) {
    faults_.store(*this, Fault::kStaleReads, static_cast<std::int64_t>(info_.max_stale_reads));
    s = DriverStatus::kFault;
  }
  return faulted(s);
}

Result Driver::serves(std::size_t wanted) const {
  if (wanted >= 1 && wanted <= axes_) return Result::success();
  const auto count = [](std::size_t n) { return std::to_string(n) + (n == 1 ? " axis" : " axes"); };
  return Result::failure("axes: the " + std::string(type()) + " driver serves " + count(axes_) +
                         ", the configuration names " + count(wanted));
}

DriverStatus Driver::safe_state() noexcept {
  output_v_.store(info_.safe_output_v, std::memory_order_relaxed);
  if (state_.load(std::memory_order_relaxed) != State::kActive) return DriverStatus::kOk;
  return driver_->safe_state();
}

void Driver::set_run_active(bool active) noexcept {
  if (state_.load(std::memory_order_relaxed) == State::kActive) driver_->set_run_active(active);
}

std::string Driver::describe_fault(int cause, std::int64_t detail) const {
  switch (static_cast<Fault>(cause)) {
    case Fault::kStaleReads:
      return "no fresh measurement for max_stale_reads = " + std::to_string(detail) +
             " reads in a row";
    case Fault::kNone:
      break;
  }
  return "";
}

nlohmann::json Driver::diagnostics() const {
  nlohmann::json d = driver_->diagnostics();
  d["active"] = state() == State::kActive;
  d["output_v"] = output_v_.load(std::memory_order_relaxed);
  d["position_um"] = position_um_.load(std::memory_order_relaxed);
  d["stale_reads"] = stale_reads_.load(std::memory_order_relaxed);
  d["max_rate_hz"] = info_.max_rate_hz;
  d["axes"] = axes_;
  const std::string fault = faults_.describe();
  d["last_fault"] = fault.empty() ? std::string("none") : fault;
  return d;
}

}  // namespace hystbench::drivers
