#include "hystbench/drivers/modbus_daq.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <ctime>
#include <vector>

#include "details/modbus_link.hpp"
#include "details/rtt_histogram.hpp"
#include "details/triple_buffer.hpp"

namespace hystbench::drivers {

using details::ModbusLink;
using details::monotonic_ns;

namespace {
constexpr int kActivationExchanges = 100;
constexpr std::int64_t kIdlePollNs = 20'000'000;  // I/O thread: an exchange at least this often

std::string fmt(double v, int digits = 1) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}
}  // namespace

ModbusDaqDriver::ModbusDaqDriver()
    : rtt_(std::make_unique<details::RttHistogram>()),
      samples_(std::make_unique<details::TripleBuffer<Sample>>()) {
  sem_init(&wake_, 0, 0);
}

ModbusDaqDriver::~ModbusDaqDriver() {
  stop_io_thread();
  sem_destroy(&wake_);
}

Result ModbusDaqDriver::configure(const nlohmann::json& params, double rate_hz) {
  if (active_) return Result::failure("driver.modbus: configure() while active");
  try {
    config_ = parse_modbus_daq_config(params);
  } catch (const std::exception& e) {
    return Result::failure(e.what());
  }
  if (!(rate_hz > 0.0)) return Result::failure("loop.rate_hz: must be > 0");
  if (config_.io == ModbusDaqConfig::IoMode::kLoop && rate_hz > config_.max_rate_hz) {
    return Result::failure(
        "loop.rate_hz: " + fmt(rate_hz, 0) + " Hz is beyond what the Modbus DAQ holds with io = " +
        "\"loop\" (" + config_.endpoint() + ": at most " + fmt(config_.max_rate_hz, 0) +
        " Hz, driver.modbus.max_rate_hz): lower loop.rate_hz or set driver.modbus.io = "
        "\"thread\"");
  }
  rate_hz_ = rate_hz;
  max_stale_reads_ =
      config_.max_stale_reads > 0
          ? config_.max_stale_reads
          : std::max<std::uint64_t>(10, static_cast<std::uint64_t>(std::ceil(rate_hz * 0.02)));
  try {
    link_ = std::make_unique<ModbusLink>(config_);
  } catch (const std::exception& e) {
    return Result::failure(e.what());
  }
  configured_ = true;
  return Result::success();
}

int ModbusDaqDriver::link_up(std::int64_t now_ns) noexcept {
  if (link_->connected()) return 1;
  if (now_ns < next_connect_ns_) return 0;
  if (!link_->connect()) {
    next_connect_ns_ = now_ns + static_cast<std::int64_t>(config_.reconnect_interval_ms * 1e6);
    connected_.store(false, std::memory_order_relaxed);
    return -1;
  }
  reconnects_.fetch_add(1, std::memory_order_relaxed);
  connected_.store(true, std::memory_order_relaxed);
  return 1;
}

bool ModbusDaqDriver::exchange(double output_v, bool write, bool read, double& y) noexcept {
  const int up = link_up(monotonic_ns());
  if (up == 0) return false;  // waiting for the next connection attempt: nothing was tried
  bool ok = up > 0;
  if (ok) {
    std::uint16_t out[2] = {0, 0}, in[2] = {0, 0};
    config_.output.encode(output_v, out);
    std::int64_t rtt[2] = {0, 0};
    const int n = link_->exchange(out, in, write, read, rtt);
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
    connected_.store(link_->connected(), std::memory_order_relaxed);
  }
  return ok;
}

Result ModbusDaqDriver::activate() {
  if (!configured_) return Result::failure("driver.modbus: activate() before configure()");
  if (active_) return Result::success();
  next_connect_ns_ = 0;
  if (!link_->connect()) {
    return Result::failure("driver.modbus: " + ModbusLink::describe(ModbusLink::Op::kConnect,
                                                                    link_->last_errno(), config_));
  }
  connected_.store(true);
  // Both registers must answer, and the round trip decides the rate in io = "loop".
  std::vector<std::int64_t> times;
  double y = 0.0;
  for (int i = 0; i < kActivationExchanges; ++i) {
    std::uint16_t out[2] = {0, 0}, in[2] = {0, 0};
    config_.output.encode(config_.safe_output_v, out);
    std::int64_t rtt[2] = {0, 0};
    const std::int64_t t0 = monotonic_ns();
    const int n = link_->exchange(out, in, true, true, rtt);
    if (n < 0) {
      const std::string why = ModbusLink::describe(link_->last_op(), link_->last_errno(), config_);
      link_->close();
      connected_.store(false);
      return Result::failure("driver.modbus: " + why);
    }
    times.push_back(monotonic_ns() - t0);
    y = config_.measurement.decode(in);
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
        "loop.rate_hz: " + fmt(rate_hz_, 0) + " Hz gives " + fmt(1e6 / rate_hz_) +
        " us per tick, but one tick's Modbus exchange with " + config_.endpoint() + " takes " +
        fmt(activation_rtt_p90_us_) + " us (p90 of " + std::to_string(kActivationExchanges) +
        " at activation; p50 " + fmt(activation_rtt_p50_us_) + " us, p99 " +
        fmt(activation_rtt_p99_us_) + " us): lower loop.rate_hz to " +
        fmt(measured_max_rate_hz_, 0) + " or set driver.modbus.io = \"thread\"");
  }
  rtt_->clear();
  transactions_ = 0;
  failed_ = 0;
  consecutive_failures_ = 0;
  stale_reads_ = 0;
  reconnects_ = 0;
  last_errno_ = 0;
  last_op_ = 0;
  fault_cause_ = 0;
  seq_ = 0;
  last_y_ = y;
  last_position_ = y;
  age_ = 0;
  consecutive_stale_ = 0;
  command_v_.store(config_.safe_output_v);
  writes_.store(0);
  samples_->reset(Sample{y, 0, 0});
  active_.store(true);
  if (config_.io == ModbusDaqConfig::IoMode::kThread) {
    while (sem_trywait(&wake_) == 0) {
    }
    quit_.store(false);
    io_thread_ = std::thread([this] { io_thread_main(); });
  }
  return Result::success();
}

void ModbusDaqDriver::io_thread_main() noexcept {
  while (!quit_.load(std::memory_order_acquire)) {
    timespec deadline{};
    clock_gettime(CLOCK_MONOTONIC, &deadline);
    const std::int64_t until = deadline.tv_nsec + kIdlePollNs;
    deadline.tv_sec += until / 1000000000;
    deadline.tv_nsec = until % 1000000000;
    while (sem_clockwait(&wake_, CLOCK_MONOTONIC, &deadline) != 0 && errno == EINTR) {
    }
    while (sem_trywait(&wake_) == 0) {
    }
    if (quit_.load(std::memory_order_acquire)) break;
    double y = 0.0;
    std::uint64_t command = 0;
    const double u = load_command(command);
    if (exchange(u, true, true, y)) {
      samples_->publish(Sample{y, ++seq_, command});
    } else if (!link_->connected()) {
      // Do not spin on a dead link: wait for the next attempt unless told to quit.
      const std::int64_t wait = std::max<std::int64_t>(0, next_connect_ns_ - monotonic_ns());
      timespec ts{};
      clock_gettime(CLOCK_MONOTONIC, &ts);
      const std::int64_t ns = ts.tv_nsec + std::min<std::int64_t>(wait, kIdlePollNs);
      ts.tv_sec += ns / 1000000000;
      ts.tv_nsec = ns % 1000000000;
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    }
  }
}

void ModbusDaqDriver::stop_io_thread() noexcept {
  if (!io_thread_.joinable()) return;
  quit_.store(true, std::memory_order_release);
  sem_post(&wake_);
  io_thread_.join();
}

Result ModbusDaqDriver::write_safe_now() {
  double y = 0.0;
  if (exchange(config_.safe_output_v, true, false, y)) return Result::success();
  return Result::failure(
      "driver.modbus: could not write the safe output " + fmt(config_.safe_output_v, 3) +
      " V: " + ModbusLink::describe(link_->last_op(), link_->last_errno(), config_));
}

Result ModbusDaqDriver::deactivate() {
  if (!active_) return Result::success();
  stop_io_thread();
  active_ = false;
  next_connect_ns_ = 0;
  Result r = write_safe_now();
  link_->close();
  connected_.store(false);
  return r;
}

Result ModbusDaqDriver::on_error() {
  command_v_.store(config_.safe_output_v);
  stop_io_thread();
  next_connect_ns_ = 0;
  Result r = link_ ? write_safe_now() : Result::success();
  if (link_) link_->close();
  connected_.store(false);
  active_ = false;
  return r;
}

void ModbusDaqDriver::publish_command(double output_v, bool count) noexcept {
  const std::uint64_t seq = command_seq_.load(std::memory_order_relaxed);
  command_seq_.store(seq + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  command_v_.store(output_v, std::memory_order_relaxed);
  if (count) writes_.store(writes_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  command_seq_.store(seq + 2, std::memory_order_release);
}

double ModbusDaqDriver::load_command(std::uint64_t& writes) const noexcept {
  for (;;) {
    const std::uint64_t before = command_seq_.load(std::memory_order_acquire);
    const double v = command_v_.load(std::memory_order_relaxed);
    writes = writes_.load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if ((before & 1) == 0 && command_seq_.load(std::memory_order_relaxed) == before) return v;
  }
}

DriverStatus ModbusDaqDriver::write(double output_v) noexcept {
  if (!active_) return DriverStatus::kFault;
  publish_command(output_v, true);
  if (config_.io == ModbusDaqConfig::IoMode::kThread) {
    sem_post(&wake_);
    return DriverStatus::kOk;
  }
  if (!config_.write_read) {
    double y = 0.0;
    exchange(output_v, true, false, y);  // a failure counts; read() reports it
  }
  return DriverStatus::kOk;
}

DriverStatus ModbusDaqDriver::read_status() noexcept {
  if (consecutive_failures_.load(std::memory_order_relaxed) >= config_.max_failed_transactions) {
    fault_cause_.store(1, std::memory_order_relaxed);
    return DriverStatus::kFault;
  }
  if (consecutive_stale_ >= max_stale_reads_) {
    fault_cause_.store(2, std::memory_order_relaxed);
    return DriverStatus::kFault;
  }
  return DriverStatus::kStale;
}

DriverStatus ModbusDaqDriver::read(Measurement& out) noexcept {
  if (!active_) return DriverStatus::kFault;
  bool fresh = false;
  std::uint64_t response = 0;
  if (config_.io == ModbusDaqConfig::IoMode::kThread) {
    Sample s;
    fresh = samples_->take(s);
    if (fresh) {
      last_y_ = s.position_um;
      const std::uint64_t writes = writes_.load(std::memory_order_relaxed);
      response = writes > s.command ? writes - s.command : 0;
    }
  } else {
    double y = 0.0;
    fresh = exchange(command_v_.load(std::memory_order_relaxed), config_.write_read, true, y);
    if (fresh) last_y_ = y;
  }
  if (fresh) {
    age_ = 0;
    consecutive_stale_ = 0;
    last_position_.store(last_y_, std::memory_order_relaxed);
    out = {last_y_, 0, response};
    return DriverStatus::kOk;
  }
  ++age_;
  ++consecutive_stale_;
  stale_reads_.fetch_add(1, std::memory_order_relaxed);
  out = {last_y_, age_};
  return read_status();
}

DriverStatus ModbusDaqDriver::safe_state() noexcept {
  publish_command(config_.safe_output_v, false);
  if (!active_) return DriverStatus::kOk;
  if (config_.io == ModbusDaqConfig::IoMode::kThread) {
    sem_post(&wake_);
    return DriverStatus::kOk;
  }
  double y = 0.0;
  return exchange(config_.safe_output_v, true, false, y) ? DriverStatus::kOk : DriverStatus::kError;
}

double ModbusDaqDriver::measurement_resolution_um() const noexcept {
  return std::abs(config_.measurement.scale);
}

double ModbusDaqDriver::max_rate_hz() const noexcept {
  if (config_.io == ModbusDaqConfig::IoMode::kThread) return 20000.0;
  return measured_max_rate_hz_ > 0.0 ? std::min(config_.max_rate_hz, measured_max_rate_hz_)
                                     : config_.max_rate_hz;
}

nlohmann::json ModbusDaqDriver::diagnostics() const {
  const int err = last_errno_.load(std::memory_order_relaxed);
  const auto op = static_cast<ModbusLink::Op>(last_op_.load(std::memory_order_relaxed));
  const std::uint64_t consecutive = consecutive_failures_.load(std::memory_order_relaxed);
  std::string fault;
  switch (fault_cause_.load(std::memory_order_relaxed)) {
    case 1:
      fault = std::to_string(consecutive) + " failed transactions in a row (max_failed_" +
              "transactions = " + std::to_string(config_.max_failed_transactions) +
              "): " + ModbusLink::describe(op, err, config_);
      break;
    case 2:
      fault = "no fresh measurement for max_stale_reads = " + std::to_string(max_stale_reads_) +
              " reads in a row";
      break;
    default:
      break;
  }
  return {{"type", "modbus"},
          {"endpoint", config_.endpoint()},
          {"io", config_.io == ModbusDaqConfig::IoMode::kThread ? "thread" : "loop"},
          {"write_read", config_.write_read},
          {"active", active_.load()},
          {"connected", connected_.load(std::memory_order_relaxed)},
          {"transactions", transactions_.load(std::memory_order_relaxed)},
          {"failed_transactions", failed_.load(std::memory_order_relaxed)},
          {"consecutive_failures", consecutive},
          {"stale_reads", stale_reads_.load(std::memory_order_relaxed)},
          {"reconnects", reconnects_.load(std::memory_order_relaxed)},
          {"last_error", err == 0 ? "" : ModbusLink::describe(op, err, config_)},
          {"last_fault", fault},
          {"output_v", command_v_.load(std::memory_order_relaxed)},
          {"position_um", last_position_.load(std::memory_order_relaxed)},
          {"max_rate_hz", max_rate_hz()},
          {"rtt_us",
           {{"count", rtt_->count()},
            {"p50", static_cast<double>(rtt_->quantile_ns(0.5)) / 1e3},
            {"p99", static_cast<double>(rtt_->quantile_ns(0.99)) / 1e3},
            {"max", static_cast<double>(rtt_->max_ns()) / 1e3}}},
          {"activation_rtt_us",
           {{"p50", activation_rtt_p50_us_},
            {"p90", activation_rtt_p90_us_},
            {"p99", activation_rtt_p99_us_}}}};
}

}  // namespace hystbench::drivers
