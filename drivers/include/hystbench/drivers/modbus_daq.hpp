#pragma once
// Modbus DAQ driver (libmodbus, TCP or RTU): the output is written to holding registers, the
// measurement read from input or holding registers, each with a linear scaling (see
// modbus_daq_config.hpp for every key and modbus_registers.hpp for the encodings).
//
// Where the transactions run (config `io`):
//   "thread" (default): an I/O thread does one exchange (write the latest command, read the
//     measurement) per loop tick, as fast as the device answers; write() and read() only touch
//     a wait-free buffer, so they are real-time safe whatever the device does. read() returns
//     kStale with age_ticks when no new measurement arrived since the previous tick; a fresh
//     one carries response_ticks, the ticks since the write() whose command its exchange took
//     (usually 1; more when the device is slow).
//   "loop": write()/read() do the transactions themselves and block for the round trip (up to
//     response_timeout_ms per transaction, plus a reconnect attempt when the link is down).
//     configure() refuses a loop rate above max_rate_hz; activate() refuses a rate whose period
//     the 90th percentile of 100 exchanges does not fit in.
// Failures: a failed transaction reads as kStale (the previous value, aged); max_failed_
// transactions failures or max_stale_reads stale reads in a row read as kFault. A fault clears
// by itself once fresh values arrive again (the link reconnects every reconnect_interval_ms).
// safe_state() commands safe_output_v (in "loop" mode it writes it at once).
// diagnostics(): connection, counters, the last error in words, round-trip percentiles.
#include <semaphore.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>

#include "hystbench/drivers/driver.hpp"
#include "hystbench/drivers/modbus_daq_config.hpp"

namespace hystbench::drivers {

namespace details {
class ModbusLink;
class RttHistogram;
template <typename T>
class TripleBuffer;
}  // namespace details

class ModbusDaqDriver final : public Driver {
 public:
  ModbusDaqDriver();
  ~ModbusDaqDriver() override;

  Result configure(const nlohmann::json& params, double rate_hz) override;
  /// Connects, checks both registers answer, measures the round trip (100 exchanges), starts the
  /// I/O thread. Fails naming the endpoint and the cause.
  Result activate() override;
  Result deactivate() override;
  Result on_error() override;

  DriverStatus write(double output_v) noexcept override;
  DriverStatus read(Measurement& out) noexcept override;
  DriverStatus safe_state() noexcept override;

  double max_rate_hz() const noexcept override;
  double output_min_v() const noexcept override { return config_.output_min_v; }
  double output_max_v() const noexcept override { return config_.output_max_v; }
  double safe_output_v() const noexcept override { return config_.safe_output_v; }
  /// |measurement.scale|: one register count.
  double measurement_resolution_um() const noexcept override;
  std::string_view type() const noexcept override { return "modbus"; }
  nlohmann::json diagnostics() const override;

  const ModbusDaqConfig& config() const noexcept { return config_; }

 private:
  struct Sample {
    double position_um = 0.0;
    std::uint64_t seq = 0;
    std::uint64_t command = 0;  ///< write() count when the exchange took its command
  };
  void io_thread_main() noexcept;
  /// 1 connected, 0 not yet time to retry, -1 a connection attempt failed.
  int link_up(std::int64_t now_ns) noexcept;
  /// One tick's exchange on the calling thread; true and `y` on success.
  bool exchange(double output_v, bool write, bool read, double& y) noexcept;
  DriverStatus read_status() noexcept;
  void stop_io_thread() noexcept;
  Result write_safe_now();

  ModbusDaqConfig config_;
  double rate_hz_ = 0.0;
  std::uint64_t max_stale_reads_ = 100;
  std::unique_ptr<details::ModbusLink> link_;
  std::unique_ptr<details::RttHistogram> rtt_;
  std::unique_ptr<details::TripleBuffer<Sample>> samples_;
  bool configured_ = false;
  std::atomic<bool> active_{false};

  // Command from the loop to the I/O thread with the write() count it belongs to, published
  // together under a sequence lock (command_seq_ odd while the loop thread changes them), so a
  // reading's response_ticks names the write its exchange really answered.
  std::atomic<double> command_v_{0.0};
  std::atomic<std::uint64_t> writes_{0};
  std::atomic<std::uint64_t> command_seq_{0};
  /// Loop thread: sets the command (and counts a write when `count`).
  void publish_command(double output_v, bool count) noexcept;
  /// I/O thread: the command and its write count, consistent with each other.
  double load_command(std::uint64_t& writes) const noexcept;
  sem_t wake_{};
  std::atomic<bool> quit_{false};
  std::thread io_thread_;

  // Written by the thread doing the transactions, read anywhere.
  std::atomic<bool> connected_{false};
  std::atomic<std::uint64_t> transactions_{0}, failed_{0}, consecutive_failures_{0};
  std::atomic<std::uint64_t> reconnects_{0};
  std::atomic<int> last_errno_{0};
  std::atomic<int> last_op_{0};
  std::int64_t next_connect_ns_ = 0;  // owned by the thread doing the transactions
  std::uint64_t seq_ = 0;             // ditto

  // Loop-thread state.
  double last_y_ = 0.0;
  std::uint64_t age_ = 0;
  std::uint64_t consecutive_stale_ = 0;
  std::atomic<std::uint64_t> stale_reads_{0};
  std::atomic<int> fault_cause_{0};  // last fault: 0 none, 1 failures, 2 stale reads
  std::atomic<double> last_position_{0.0};

  // Measured at activation.
  double activation_rtt_p50_us_ = 0.0, activation_rtt_p90_us_ = 0.0, activation_rtt_p99_us_ = 0.0;
  double measured_max_rate_hz_ = 0.0;
};

}  // namespace hystbench::drivers
