#pragma once
// Fixed-rate loop timing on absolute CLOCK_MONOTONIC deadlines (clock_nanosleep with
// TIMER_ABSTIME), so the rate does not drift with the work time or the wake-up latency.
// Deadlines are start + k * period. When wait() is entered after its deadline the tick runs
// at once (late, its latency shows it); when it is entered a whole period or more late, the
// deadlines passed over are skipped (Tick::skipped) and the grid phase is kept, so tick k is
// always at start + k * period and a controller sees the real sample time.
// wait() and now_ns() are real-time safe: no allocation, no exception, one system call.
#include <chrono>
#include <cstdint>

namespace hystbench::daemon {

class LoopTimer {
 public:
  struct Tick {
    std::uint64_t index = 0;        ///< k: this tick's deadline is start + k * period
    std::int64_t scheduled_ns = 0;  ///< the deadline, absolute CLOCK_MONOTONIC [ns]
    std::int64_t wake_ns = 0;       ///< when wait() returned, absolute CLOCK_MONOTONIC [ns]
    std::uint64_t skipped = 0;      ///< deadlines passed over since the previous tick
    std::int64_t latency_ns() const noexcept { return wake_ns - scheduled_ns; }
  };

  /// period in [1 µs, 1 s] (1 Hz .. 1 MHz); throws std::invalid_argument outside.
  explicit LoopTimer(std::chrono::nanoseconds period);

  /// Sets the first deadline to `first_deadline_ns` (absolute CLOCK_MONOTONIC).
  void start(std::int64_t first_deadline_ns) noexcept;
  /// Sets the first deadline one period from now.
  void start() noexcept { start(now_ns() + period_ns_); }

  /// Sleeps until the next deadline (see the skipping rule above). start() must come first.
  Tick wait() noexcept;

  /// True when work that ended at `end_ns` ran past the deadline after `tick`'s.
  bool overran(const Tick& tick, std::int64_t end_ns) const noexcept {
    return end_ns > tick.scheduled_ns + period_ns_;
  }

  std::int64_t period_ns() const noexcept { return period_ns_; }
  std::int64_t start_ns() const noexcept { return start_ns_; }
  std::int64_t next_deadline_ns() const noexcept { return next_ns_; }

  /// CLOCK_MONOTONIC now [ns].
  static std::int64_t now_ns() noexcept;

 private:
  std::int64_t period_ns_;
  std::int64_t start_ns_ = 0;
  std::int64_t next_ns_ = 0;
  std::uint64_t next_index_ = 0;
};

}  // namespace hystbench::daemon
