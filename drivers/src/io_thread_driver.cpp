#include "hystbench/drivers/io_thread_driver.hpp"

#include <cerrno>
#include <ctime>
#include <string>

#include "details/triple_buffer.hpp"

namespace hystbench::drivers {

namespace {
constexpr std::int64_t kIdlePollNs = 20'000'000;  // an exchange at least this often
}  // namespace

IoThreadDriver::IoThreadDriver(std::unique_ptr<DriverInterface> inner)
    : DriverWrapper(std::move(inner)), samples_(std::make_unique<details::TripleBuffer<Sample>>()) {
  sem_init(&wake_, 0, 0);
}

IoThreadDriver::~IoThreadDriver() {
  stop();
  sem_destroy(&wake_);
}

Result IoThreadDriver::on_activate() {
  Result r = inner_->on_activate();
  threaded_ = r.ok && inner_->info().io_thread;
  if (!threaded_) return r;
  if (inner_->axes() > 1) {
    threaded_ = false;
    inner_->on_deactivate();
    return Result::failure("driver." + std::string(inner_->type()) +
                           ": its I/O thread serves one axis, this driver " +
                           std::to_string(inner_->axes()));
  }
  samples_->reset(Sample{inner_->activation_position_um(), 0});
  io_status_.store(DriverStatus::kStale);
  safe_output_v_ = inner_->info().safe_output_v;
  command_v_.store(safe_output_v_);
  writes_.store(0);
  while (sem_trywait(&wake_) == 0) {
  }
  quit_.store(false);
  thread_ = std::thread([this] { run(); });
  return r;
}

Result IoThreadDriver::on_deactivate() {
  stop();
  return inner_->on_deactivate();
}

void IoThreadDriver::stop() noexcept {
  if (!thread_.joinable()) return;
  quit_.store(true, std::memory_order_release);
  sem_post(&wake_);
  thread_.join();
}

void IoThreadDriver::run() noexcept {
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
    std::uint64_t command = 0;
    const double u = load_command(command);
    DriverStatus s = inner_->write(u);
    Measurement m;
    if (s == DriverStatus::kOk) s = inner_->read(m);
    if (s == DriverStatus::kOk) samples_->publish(Sample{m.position_um, command});
    io_status_.store(s == DriverStatus::kOk ? DriverStatus::kStale : s, std::memory_order_relaxed);
  }
}

void IoThreadDriver::command(double output_v, bool count) noexcept {
  const std::uint64_t seq = command_seq_.load(std::memory_order_relaxed);
  command_seq_.store(seq + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  command_v_.store(output_v, std::memory_order_relaxed);
  if (count) writes_.store(writes_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  command_seq_.store(seq + 2, std::memory_order_release);
  sem_post(&wake_);
}

double IoThreadDriver::load_command(std::uint64_t& writes) const noexcept {
  for (;;) {
    const std::uint64_t before = command_seq_.load(std::memory_order_acquire);
    const double v = command_v_.load(std::memory_order_relaxed);
    writes = writes_.load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if ((before & 1) == 0 && command_seq_.load(std::memory_order_relaxed) == before) return v;
  }
}

DriverStatus IoThreadDriver::write(double output_v) noexcept {
  if (!threaded_) return inner_->write(output_v);
  command(output_v, true);
  return DriverStatus::kOk;
}

DriverStatus IoThreadDriver::read(Measurement& out) noexcept {
  if (!threaded_) return inner_->read(out);
  Sample s;
  if (!samples_->take(s)) return io_status_.load(std::memory_order_relaxed);
  const std::uint64_t writes = writes_.load(std::memory_order_relaxed);
  out.position_um = s.position_um;
  out.response_ticks = writes > s.command ? writes - s.command : 0;
  return DriverStatus::kOk;
}

DriverStatus IoThreadDriver::write_axes(std::span<const double> outputs_v) noexcept {
  if (!threaded_) return inner_->write_axes(outputs_v);
  return outputs_v.empty() ? DriverStatus::kOk : write(outputs_v.front());
}

DriverStatus IoThreadDriver::read_axes(std::span<Measurement> out) noexcept {
  if (!threaded_) return inner_->read_axes(out);
  Measurement unused;
  return read(out.empty() ? unused : out.front());
}

DriverStatus IoThreadDriver::safe_state() noexcept {
  if (!threaded_) return inner_->safe_state();
  command(safe_output_v_, false);
  return DriverStatus::kOk;
}

DriverStatus IoThreadDriver::on_error() noexcept {
  if (!threaded_) return inner_->on_error();
  return safe_state();
}

}  // namespace hystbench::drivers
