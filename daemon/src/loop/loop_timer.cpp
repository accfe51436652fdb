#include "hystbench/daemon/loop/loop_timer.hpp"

#include <time.h>

#include <cerrno>
#include <stdexcept>

namespace hystbench::daemon {

namespace {

constexpr std::int64_t kNsPerS = 1'000'000'000;

}  // namespace

LoopTimer::LoopTimer(std::chrono::nanoseconds period) : period_ns_(period.count()) {
  if (period_ns_ < 1'000 || period_ns_ > kNsPerS) {
    throw std::invalid_argument("loop period must be in [1 us, 1 s], got " +
                                std::to_string(period_ns_) + " ns");
  }
}

std::int64_t LoopTimer::now_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

void LoopTimer::start(std::int64_t first_deadline_ns) noexcept {
  start_ns_ = first_deadline_ns;
  next_ns_ = first_deadline_ns;
  next_index_ = 0;
}

LoopTimer::Tick LoopTimer::wait() noexcept {
  Tick tick;
  std::int64_t now = now_ns();
  if (now - next_ns_ >= period_ns_) {
    tick.skipped = static_cast<std::uint64_t>((now - next_ns_) / period_ns_);
    next_ns_ += static_cast<std::int64_t>(tick.skipped) * period_ns_;
    next_index_ += tick.skipped;
  }
  if (now < next_ns_) {
    const timespec deadline{static_cast<time_t>(next_ns_ / kNsPerS),
                            static_cast<long>(next_ns_ % kNsPerS)};
    // Absolute deadline: an interrupted sleep is simply restarted.
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
    }
    now = now_ns();
  }
  tick.index = next_index_;
  tick.scheduled_ns = next_ns_;
  tick.wake_ns = now;
  next_ns_ += period_ns_;
  ++next_index_;
  return tick;
}

}  // namespace hystbench::daemon
