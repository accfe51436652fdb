#include "hystbench/drivers/modbus_daq.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "details/modbus_link.hpp"
#include "details/rtt_histogram.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::drivers {

using compensation::fixed;
using details::ModbusLink;
using details::monotonic_ns;

namespace {
constexpr int kActivationExchanges = 100;
constexpr double kIoThreadMaxRateHz = 20000.0;
}  // namespace

ModbusDaqDriver::ModbusDaqDriver() : rtt_(std::make_unique<details::RttHistogram>()) {}

ModbusDaqDriver::~ModbusDaqDriver() = default;

Result ModbusDaqDriver::on_configure(const nlohmann::json& params, double rate_hz) {
  try {
    config_ = parse_modbus_daq_config(params);
  } catch (const std::exception& e) {
    return Result::failure(e.what());
  }
  if (config_.io == ModbusDaqConfig::IoMode::kLoop && rate_hz > config_.max_rate_hz) {
    return Result::failure("loop.rate_hz: " + fixed(rate_hz, 0) +
                           " Hz is beyond what the Modbus DAQ holds with io = \"loop\" (" +
                           config_.endpoint() + ": at most " + fixed(config_.max_rate_hz, 0) +
                           " Hz, driver.modbus.max_rate_hz): lower loop.rate_hz or set "
                           "driver.modbus.io = \"thread\"");
  }
  rate_hz_ = rate_hz;
  measured_max_rate_hz_ = 0.0;
  max_stale_reads_ =
      config_.max_stale_reads > 0
          ? config_.max_stale_reads
          : std::max<std::uint64_t>(10, static_cast<std::uint64_t>(std::ceil(rate_hz * 0.02)));
  try {
    link_ = std::make_unique<ModbusLink>(config_);
  } catch (const std::exception& e) {
    return Result::failure(e.what());
  }
  return Result::success();
}

ModbusDaqDriver::Link ModbusDaqDriver::link_up(std::int64_t now_ns) noexcept {
  if (link_->connected()) return Link::kUp;
  if (now_ns < next_connect_ns_) return Link::kWaiting;
  if (!link_->connect()) {
    next_connect_ns_ = now_ns + static_cast<std::int64_t>(config_.reconnect_interval_ms * 1e6);
    connected_.store(false, std::memory_order_relaxed);
    return Link::kFailed;
  }
  reconnects_.fetch_add(1, std::memory_order_relaxed);
  connected_.store(true, std::memory_order_relaxed);
  return Link::kUp;
}

bool ModbusDaqDriver::exchange(std::size_t axis, double output_v, bool write, bool read,
                               double& y) noexcept {
  const Link link = link_up(monotonic_ns());
  if (link == Link::kWaiting) return false;  // nothing was tried
  bool ok = link == Link::kUp;
  if (ok) {
    std::uint16_t out[2] = {0, 0}, in[2] = {0, 0};
    config_.output.encode(output_v, out);
    std::int64_t rtt[2] = {0, 0};
    const int n = link_->exchange(out, in, write, read, rtt, config_.axis_offset(axis));
    ok = n >= 0;
    for (int i = 0; i < n; ++i) rtt_->record(rtt[i]);
    transactions_.fetch_add(n > 0 ? n : 1, std::memory_order_relaxed);
    if (ok && read) y = config_.measurement.decode(in);
  }
  if (ok) {
    consecutive_failures_.store(0, std::memory_order_relaxed);
  } else {
    failed_.fetch_add(1, std::memory_order_relaxed);
    consecutive_failures_.fetch_add(1, std::memory_order_relaxed);
    last_errno_.store(link_->last_errno(), std::memory_order_relaxed);
    last_op_.store(static_cast<int>(link_->last_op()), std::memory_order_relaxed);
    last_offset_.store(config_.axis_offset(axis), std::memory_order_relaxed);
    connected_.store(link_->connected(), std::memory_order_relaxed);
  }
  return ok;
}

Result ModbusDaqDriver::on_activate() {
  next_connect_ns_ = 0;
  if (!link_->connect()) {
    return Result::failure("driver.modbus: " + ModbusLink::describe(ModbusLink::Op::kConnect,
                                                                    link_->last_errno(), config_));
  }
  connected_.store(true);
  // Both registers of every axis must answer, and the round trip of a tick (every axis's
  // exchange) decides the rate in io = "loop".
  std::vector<std::int64_t> times;
  double y = 0.0;
  for (int i = 0; i < kActivationExchanges; ++i) {
    const std::int64_t t0 = monotonic_ns();
    for (std::size_t a = 0; a < axes(); ++a) {
      std::uint16_t out[2] = {0, 0}, in[2] = {0, 0};
      config_.output.encode(config_.safe_output_v, out);
      std::int64_t rtt[2] = {0, 0};
      const int offset = config_.axis_offset(a);
      if (link_->exchange(out, in, true, true, rtt, offset) < 0) {
        const std::string why =
            ModbusLink::describe(link_->last_op(), link_->last_errno(), config_, offset);
        link_->close();
        connected_.store(false);
        return Result::failure("driver.modbus: " + why);
      }
      if (a == 0) y = config_.measurement.decode(in);
    }
    times.push_back(monotonic_ns() - t0);
  }
  std::sort(times.begin(), times.end());
  const auto pct = [&](double q) {
    return static_cast<double>(times[static_cast<std::size_t>(q * (times.size() - 1))]) / 1e3;
  };
  activation_rtt_p50_us_ = pct(0.5);
  activation_rtt_p90_us_ = pct(0.9);
  activation_rtt_p99_us_ = pct(0.99);
  // The 90th percentile decides: a rare late answer is an overrun the loop counts, a typical
  // one that does not fit the period is a rate the link cannot hold.
  measured_max_rate_hz_ = std::floor(1e6 / std::max(activation_rtt_p90_us_, 1.0));
  if (config_.io == ModbusDaqConfig::IoMode::kLoop && rate_hz_ > measured_max_rate_hz_) {
    link_->close();
    connected_.store(false);
    return Result::failure(
        "loop.rate_hz: " + fixed(rate_hz_, 0) + " Hz gives " + fixed(1e6 / rate_hz_, 1) +
        " us per tick, but one tick's Modbus exchange with " + config_.endpoint() + " takes " +
        fixed(activation_rtt_p90_us_, 1) + " us (p90 of " + std::to_string(kActivationExchanges) +
        " at activation; p50 " + fixed(activation_rtt_p50_us_, 1) + " us, p99 " +
        fixed(activation_rtt_p99_us_, 1) + " us): lower loop.rate_hz to " +
        fixed(measured_max_rate_hz_, 0) + " or set driver.modbus.io = \"thread\"");
  }
  rtt_->clear();
  transactions_ = 0;
  failed_ = 0;
  consecutive_failures_ = 0;
  reconnects_ = 0;
  last_errno_ = 0;
  last_op_ = 0;
  last_offset_ = 0;
  activation_y_ = y;
  command_v_.fill(config_.safe_output_v);
  write_failed_ = false;
  return Result::success();
}

Result ModbusDaqDriver::write_safe_now() {
  if (safe_state() == DriverStatus::kOk) return Result::success();
  return Result::failure("driver.modbus: could not write the safe output " +
                         fixed(config_.safe_output_v, 3) + " V: " +
                         ModbusLink::describe(link_->last_op(), link_->last_errno(), config_,
                                              last_offset_.load(std::memory_order_relaxed)));
}

Result ModbusDaqDriver::on_deactivate() {
  next_connect_ns_ = 0;
  Result r = write_safe_now();
  link_->close();
  connected_.store(false);
  return r;
}

DriverStatus ModbusDaqDriver::write(double output_v) noexcept {
  return write_axes(std::span<const double>(&output_v, 1));
}

DriverStatus ModbusDaqDriver::write_axes(std::span<const double> outputs_v) noexcept {
  // With write_read the output goes out with the measurement, in read_axes()'s function 23.
  write_failed_ = false;
  for (std::size_t a = 0; a < outputs_v.size() && a < axes(); ++a) {
    command_v_[a] = outputs_v[a];
    double y = 0.0;
    if (!config_.write_read && !exchange(a, outputs_v[a], true, false, y)) {
      write_failed_ = true;
      break;
    }
  }
  return DriverStatus::kOk;  // a failure counts; read_axes() reports it
}

DriverStatus ModbusDaqDriver::read(Measurement& out) noexcept {
  return read_axes(std::span<Measurement>(&out, 1));
}

DriverStatus ModbusDaqDriver::read_axes(std::span<Measurement> out) noexcept {
  // One exchange per axis and tick: after a failed write or read the rest is not tried.
  std::array<double, kMaxAxes> y{};
  const std::size_t n = std::min(out.size(), axes());
  bool fresh = !write_failed_;
  for (std::size_t a = 0; fresh && a < n; ++a) {
    fresh = exchange(a, command_v_[a], config_.write_read, true, y[a]);
  }
  write_failed_ = false;
  if (fresh) {
    for (std::size_t a = 0; a < n; ++a) out[a].position_um = y[a];
    return DriverStatus::kOk;
  }
  const std::uint64_t failures = consecutive_failures_.load(std::memory_order_relaxed);
  if (failures < config_.max_failed_transactions) return DriverStatus::kStale;
  report_fault(Fault::kFailedTransactions, static_cast<std::int64_t>(failures));
  return DriverStatus::kFault;
}

DriverStatus ModbusDaqDriver::safe_state() noexcept {
  DriverStatus s = DriverStatus::kOk;
  for (std::size_t a = 0; a < axes(); ++a) {
    double y = 0.0;
    command_v_[a] = config_.safe_output_v;
    if (!exchange(a, config_.safe_output_v, true, false, y)) s = DriverStatus::kError;
  }
  return s;
}

DriverInfo ModbusDaqDriver::info() const noexcept {
  DriverInfo i;
  const bool thread = config_.io == ModbusDaqConfig::IoMode::kThread;
  i.max_rate_hz = thread ? kIoThreadMaxRateHz
                  : measured_max_rate_hz_ > 0.0
                      ? std::min(config_.max_rate_hz, measured_max_rate_hz_)
                      : config_.max_rate_hz;
  i.output_min_v = config_.output_min_v;
  i.output_max_v = config_.output_max_v;
  i.safe_output_v = config_.safe_output_v;
  i.measurement_resolution_um = std::abs(config_.measurement.scale);
  i.max_stale_reads = max_stale_reads_;
  i.io_thread = thread;
  return i;
}

std::string ModbusDaqDriver::describe_fault(int cause, std::int64_t detail) const {
  if (static_cast<Fault>(cause) != Fault::kFailedTransactions) {
    return DriverInterface::describe_fault(cause, detail);
  }
  const auto op = static_cast<ModbusLink::Op>(last_op_.load(std::memory_order_relaxed));
  return std::to_string(detail) + " failed transactions in a row (max_failed_transactions = " +
         std::to_string(config_.max_failed_transactions) + "): " +
         ModbusLink::describe(op, last_errno_.load(std::memory_order_relaxed), config_,
                              last_offset_.load(std::memory_order_relaxed));
}

nlohmann::json ModbusDaqDriver::diagnostics() const {
  const int err = last_errno_.load(std::memory_order_relaxed);
  const auto op = static_cast<ModbusLink::Op>(last_op_.load(std::memory_order_relaxed));
  const int offset = last_offset_.load(std::memory_order_relaxed);
  nlohmann::json d = {
      {"type", "modbus"},
      {"endpoint", config_.endpoint()},
      {"io", config_.io == ModbusDaqConfig::IoMode::kThread ? "thread" : "loop"},
      {"write_read", config_.write_read},
      {"connected", connected_.load(std::memory_order_relaxed)},
      {"transactions", transactions_.load(std::memory_order_relaxed)},
      {"failed_transactions", failed_.load(std::memory_order_relaxed)},
      {"consecutive_failures", consecutive_failures_.load(std::memory_order_relaxed)},
      {"reconnects", reconnects_.load(std::memory_order_relaxed)},
      {"last_error", err == 0 ? "" : ModbusLink::describe(op, err, config_, offset)},
      {"rtt_us",
       {{"count", rtt_->count()},
        {"p50", static_cast<double>(rtt_->quantile_ns(0.5)) / 1e3},
        {"p99", static_cast<double>(rtt_->quantile_ns(0.99)) / 1e3},
        {"max", static_cast<double>(rtt_->max_ns()) / 1e3}}},
      {"activation_rtt_us",
       {{"p50", activation_rtt_p50_us_},
        {"p90", activation_rtt_p90_us_},
        {"p99", activation_rtt_p99_us_}}}};
  // A stage's blocks.
  if (!config_.axes.empty()) {
    d["axis_names"] = config_.axes;
    d["axis_stride"] = config_.axis_stride;
  }
  return d;
}

}  // namespace hystbench::drivers
