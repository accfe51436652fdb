#pragma once
// Asynchronous I/O for any driver whose write()/read() block for a round trip: wraps it (like
// GpioDriver) and, when the configured driver asks for it (DriverInfo::io_thread, e.g. Modbus
// `io = "thread"`), runs the wrapped driver's write() and read() on an I/O thread, one exchange
// per loop tick (woken by write(), at least every 20 ms), as fast as the device answers.
// Otherwise it only forwards.
// Loop side with the thread: write(), read(), safe_state(), on_error() only touch a wait-free
// triple buffer, a sequence-locked command and a semaphore, so they are real-time safe whatever
// the device does. read() is kOk with a new measurement, whose response_ticks counts the
// write()s since the exchange took its command (usually 1; more when the device is slow);
// otherwise the status of the last exchange (kStale, or kFault while the driver reports one).
// safe_state()/on_error() make the safe output the command of the next exchange.
// A wrapped driver of several axes: every exchange is its write_axes() then read_axes(), with
// the commands of the last write_axes() (write() changes the first axis's only).
// Thread side: the wrapped driver's write() then read(), and its fault reports, on the I/O
// thread; its lifecycle hooks on the caller's thread while the I/O thread is stopped.
#include <semaphore.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>

#include "hystbench/drivers/driver_wrapper.hpp"

namespace hystbench::drivers {

namespace details {
template <typename T>
class TripleBuffer;
}  // namespace details

class IoThreadDriver final : public DriverWrapper {
 public:
  explicit IoThreadDriver(std::unique_ptr<DriverInterface> inner);
  ~IoThreadDriver() override;

  /// Activates the wrapped driver, then starts the I/O thread if its info() asks for one.
  Result on_activate() override;
  /// Stops the I/O thread, then deactivates the wrapped driver.
  Result on_deactivate() override;
  DriverStatus on_error() noexcept override;

  DriverStatus write(double output_v) noexcept override;
  DriverStatus read(Measurement& out) noexcept override;
  /// Without the thread, the wrapped driver's; with it, every axis's command and measurement.
  DriverStatus write_axes(std::span<const double> outputs_v) noexcept override;
  DriverStatus read_axes(std::span<Measurement> out) noexcept override;
  DriverStatus safe_state() noexcept override;

 private:
  struct Sample {
    std::array<double, kMaxAxes> position_um{};
    std::uint64_t command = 0;  ///< write() count when the exchange took its command
  };
  void run() noexcept;
  void stop() noexcept;
  /// Loop thread: sets the commands of the first outputs_v.size() axes (and counts a write
  /// when `count`), wakes the I/O thread.
  void command(std::span<const double> outputs_v, bool count) noexcept;
  /// I/O thread: every axis's command and their write count, consistent with each other.
  void load_command(std::span<double> outputs_v, std::uint64_t& writes) const noexcept;

  bool threaded_ = false;
  std::size_t axes_ = 1;
  double safe_output_v_ = 0.0;
  std::unique_ptr<details::TripleBuffer<Sample>> samples_;
  std::atomic<DriverStatus> io_status_{DriverStatus::kStale};  ///< of the last exchange

  // The command and the write() count it belongs to, published together under a sequence lock
  // (command_seq_ odd while the loop thread changes them), so a reading's response_ticks names
  // the write its exchange really answered.
  std::array<std::atomic<double>, kMaxAxes> command_v_{};
  std::atomic<std::uint64_t> writes_{0};
  std::atomic<std::uint64_t> command_seq_{0};
  sem_t wake_{};
  std::atomic<bool> quit_{false};
  std::thread thread_;
};

}  // namespace hystbench::drivers
