#pragma once
// Modbus DAQ driver (libmodbus, TCP or RTU): the output is written to holding registers, the
// measurement read from input or holding registers, each with a linear scaling (see
// modbus_daq_config.hpp for every key and modbus_registers.hpp for the encodings).
//
// One exchange per tick, blocking for the round trip (up to response_timeout_ms per transaction,
// plus a reconnect attempt when the link is down): write() writes the output registers, read()
// reads the measurement (not tried after a failed write); with write_read, read() does both in
// one function-23 transaction.
// Where that runs (config `io`; registered as make_interface<ModbusDaqDriver, IoThreadDriver>):
//   "thread" (default): on IoThreadDriver's I/O thread (DriverInfo::io_thread), so the loop
//     never waits for the device;
//   "loop": in the tick. on_configure() refuses a loop rate above max_rate_hz; on_activate()
//     refuses a rate whose period the 90th percentile of 100 exchanges does not fit in.
// Failures: a failed transaction reads as kStale; max_failed_transactions failures in a row read
// as kFault (and max_stale_reads stale reads in a row, counted by the framework). A fault clears
// by itself once fresh values arrive again (the link reconnects every reconnect_interval_ms).
// safe_state() writes safe_output_v at once.
// A stage (config `axes`): each axis has its register block; write_axes()/read_axes() exchange
// every axis in turn in one tick (2 transactions per axis, 1 with write_read), fresh only when
// every axis answered; write()/read() serve the first axis while the others hold their output.
// diagnostics(): connection, counters, the last error in words, round-trip percentiles.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>

#include "hystbench/drivers/driver_interface.hpp"
#include "hystbench/drivers/modbus_daq_config.hpp"

namespace hystbench::drivers {

namespace details {
class ModbusLink;
class RttHistogram;
}  // namespace details

class ModbusDaqDriver final : public DriverInterface {
 public:
  enum class Fault : int { kNone = 0, kFailedTransactions };

  ModbusDaqDriver();
  ~ModbusDaqDriver() override;

  Result on_configure(const nlohmann::json& params, double rate_hz) override;
  /// Connects, checks both registers answer, measures the round trip (100 exchanges). Fails
  /// naming the endpoint and the cause.
  Result on_activate() override;
  /// Writes the safe output and closes the link.
  Result on_deactivate() override;

  /// Writes the output registers (with write_read: only takes the command for read()).
  DriverStatus write(double output_v) noexcept override;
  /// Reads the measurement (with write_read: function 23 with the command).
  DriverStatus read(Measurement& out) noexcept override;
  /// Every axis's output registers, axis by axis (with write_read: only takes the commands).
  DriverStatus write_axes(std::span<const double> outputs_v) noexcept override;
  /// Every axis's measurement, axis by axis: kOk only when all of them answered.
  DriverStatus read_axes(std::span<Measurement> out) noexcept override;
  /// The safe output on every axis.
  DriverStatus safe_state() noexcept override;
  std::size_t axes() const noexcept override { return config_.axis_count(); }

  /// measurement_resolution_um = |measurement.scale| (one register count); max_rate_hz with
  /// io = "loop": driver.modbus.max_rate_hz, after activation at most what the round trip allows.
  DriverInfo info() const noexcept override;
  double activation_position_um() const noexcept override { return activation_y_; }
  std::string_view type() const noexcept override { return "modbus"; }
  nlohmann::json diagnostics() const override;
  std::string describe_fault(int cause, std::int64_t detail) const override;

  const ModbusDaqConfig& config() const noexcept { return config_; }

 private:
  enum class Link : std::uint8_t { kUp, kWaiting, kFailed };
  /// Connects when it is time to; kWaiting until the next attempt.
  Link link_up(std::int64_t now_ns) noexcept;
  /// One exchange with axis `axis`'s block on the calling thread; true and `y` on success.
  bool exchange(std::size_t axis, double output_v, bool write, bool read, double& y) noexcept;
  Result write_safe_now();

  ModbusDaqConfig config_;
  double rate_hz_ = 0.0;
  std::uint64_t max_stale_reads_ = 100;
  std::unique_ptr<details::ModbusLink> link_;
  std::unique_ptr<details::RttHistogram> rtt_;

  // The thread doing the transactions (the loop's or the I/O thread).
  std::array<double, kMaxAxes> command_v_{};
  bool write_failed_ = false;  ///< this tick's write(); read() then does not try
  std::int64_t next_connect_ns_ = 0;

  // Written by the thread doing the transactions, read anywhere.
  std::atomic<bool> connected_{false};
  std::atomic<std::uint64_t> transactions_{0}, failed_{0}, consecutive_failures_{0};
  std::atomic<std::uint64_t> reconnects_{0};
  std::atomic<int> last_errno_{0};
  std::atomic<int> last_op_{0};
  std::atomic<int> last_offset_{0};  ///< the register block of the last failure

  // Measured at activation.
  double activation_y_ = 0.0;
  double activation_rtt_p50_us_ = 0.0, activation_rtt_p90_us_ = 0.0, activation_rtt_p99_us_ = 0.0;
  double measured_max_rate_hz_ = 0.0;
};

}  // namespace hystbench::drivers
