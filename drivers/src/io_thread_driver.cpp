#include "hystbench/drivers/io_thread_driver.hpp"

#include <algorithm>
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
  axes_ = std::min(inner_->axes(), kMaxAxes);
  Sample first;
  first.position_um[0] = inner_->activation_position_um();
  samples_->reset(first);
  io_status_.store(DriverStatus::kStale);
  safe_output_v_ = inner_->info().safe_output_v;
  for (auto& c : command_v_) c.store(safe_output_v_);
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
    std::array<double, kMaxAxes> u{};
    load_command(std::span<double>(u).first(axes_), command);
    DriverStatus s = inner_->write_axes(std::span<const double>(u).first(axes_));
    std::array<Measurement, kMaxAxes> m{};
    if (s == DriverStatus::kOk) s = inner_->read_axes(std::span<Measurement>(m).first(axes_));
    if (s == DriverStatus::kOk) {
      Sample sample;
      for (std::size_t a = 0; a < axes_; ++a) sample.position_um[a] = m[a].position_um;
      sample.command = command;
      samples_->publish(sample);
    }
    io_status_.store(s == DriverStatus::kOk ? DriverStatus::kStale : s, std::memory_order_relaxed);
  }
}

void IoThreadDriver::command(std::span<const double> outputs_v, bool count) noexcept {
  const std::uint64_t seq = command_seq_.load(std::memory_order_relaxed);
  command_seq_.store(seq + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  for (std::size_t a = 0; a < outputs_v.size() && a < axes_; ++a) {
    command_v_[a].store(outputs_v[a], std::memory_order_relaxed);
  }
  if (count) writes_.store(writes_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  command_seq_.store(seq + 2, std::memory_order_release);
  sem_post(&wake_);
}

void IoThreadDriver::load_command(std::span<double> outputs_v,
                                  std::uint64_t& writes) const noexcept {
  for (;;) {
    const std::uint64_t before = command_seq_.load(std::memory_order_acquire);
    for (std::size_t a = 0; a < outputs_v.size(); ++a) {
      outputs_v[a] = command_v_[a].load(std::memory_order_relaxed);
    }
    writes = writes_.load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if ((before & 1) == 0 && command_seq_.load(std::memory_order_relaxed) == before) return;
  }
}

DriverStatus IoThreadDriver::write(double output_v) noexcept {
  if (!threaded_) return inner_->write(output_v);
  return write_axes(std::span<const double>(&output_v, 1));
}

DriverStatus IoThreadDriver::read(Measurement& out) noexcept {
  if (!threaded_) return inner_->read(out);
  return read_axes(std::span<Measurement>(&out, 1));
}

DriverStatus IoThreadDriver::write_axes(std::span<const double> outputs_v) noexcept {
  if (!threaded_) return inner_->write_axes(outputs_v);
  command(outputs_v, true);
  return DriverStatus::kOk;
}

DriverStatus IoThreadDriver::read_axes(std::span<Measurement> out) noexcept {
  if (!threaded_) return inner_->read_axes(out);
  Sample s;
  if (!samples_->take(s)) return io_status_.load(std::memory_order_relaxed);
  const std::uint64_t writes = writes_.load(std::memory_order_relaxed);
  for (std::size_t a = 0; a < out.size() && a < axes_; ++a) {
    out[a].position_um = s.position_um[a];
    out[a].response_ticks = writes > s.command ? writes - s.command : 0;
  }
  return DriverStatus::kOk;
}

DriverStatus IoThreadDriver::safe_state() noexcept {
  if (!threaded_) return inner_->safe_state();
  std::array<double, kMaxAxes> safe{};
  safe.fill(safe_output_v_);
  command(std::span<const double>(safe).first(axes_), false);
  return DriverStatus::kOk;
}

DriverStatus IoThreadDriver::on_error() noexcept {
  if (!threaded_) return inner_->on_error();
  return safe_state();
}

}  // namespace hystbench::drivers
