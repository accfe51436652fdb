#pragma once
// Real-time setup of the calling thread / process: SCHED_FIFO priority, CPU affinity, locked
// memory. Each step returns a RealtimeStatus instead of throwing, so the loop thread can apply
// them and the daemon can say once "real-time scheduling not permitted, running degraded".
// None of these are for the loop's hot path (they make system calls); call them before it.
// Permissions: SCHED_FIFO needs CAP_SYS_NICE or RLIMIT_RTPRIO >= priority; mlockall needs
// CAP_IPC_LOCK or an unlimited RLIMIT_MEMLOCK. (With MCL_FUTURE under a finite limit every later
// allocation past it would fail, so lock_memory() refuses with EPERM then, locking nothing.)
#include <cstddef>
#include <string>

namespace hystbench::daemon {

struct RealtimeStatus {
  int error = 0;          ///< 0 = done; otherwise an errno value (EPERM = not permitted)
  const char* step = "";  ///< the call that failed, e.g. "sched_setscheduler"

  bool ok() const noexcept { return error == 0; }
  bool not_permitted() const noexcept;  ///< EPERM / EACCES
  /// "sched_setscheduler: Operation not permitted" or "ok". Allocates.
  std::string describe() const;
};

/// SCHED_FIFO at `priority` in [1, 99] for the calling thread (EINVAL outside).
RealtimeStatus set_fifo_priority(int priority) noexcept;
/// SCHED_OTHER, nice 0 for the calling thread (helper threads started from a real-time thread
/// inherit its policy; they call this first).
RealtimeStatus set_normal_scheduling() noexcept;
/// Timer slack of the calling thread (prctl PR_SET_TIMERSLACK): how late the kernel may wake a
/// SCHED_OTHER sleeper to batch wake-ups (default 50 µs). SCHED_FIFO threads have none.
RealtimeStatus set_timer_slack(long nanoseconds) noexcept;
/// Pins the calling thread to one CPU; cpu < 0 does nothing and returns ok.
RealtimeStatus pin_to_cpu(int cpu) noexcept;
/// mlockall(MCL_CURRENT | MCL_FUTURE), see the note above; undo with unlock_memory().
RealtimeStatus lock_memory() noexcept;
RealtimeStatus unlock_memory() noexcept;
/// Touches `bytes` of the calling thread's stack so the loop takes no page fault on it later.
void prefault_stack(std::size_t bytes = std::size_t{256} * 1024) noexcept;

struct RealtimeOptions {
  bool fifo = true;   ///< try SCHED_FIFO
  int priority = 80;  ///< [1, 99]
  int cpu = -1;       ///< -1 = no affinity
  bool lock_memory = true;
};

/// What apply_realtime() achieved, step by step.
struct RealtimeReport {
  RealtimeStatus scheduling;  ///< ok also when not requested
  RealtimeStatus affinity;
  RealtimeStatus memory;
  /// The loop runs on the simulated clock: SCHED_FIFO and the memory lock were not taken.
  bool simulated_clock = false;
  bool degraded() const noexcept { return !scheduling.ok() || !affinity.ok() || !memory.ok(); }
  /// One line for the log, e.g. "real-time: SCHED_FIFO 80 ok, cpu 3 ok, mlockall: Operation
  /// not permitted (running degraded)", or with the simulated clock "real-time: simulated clock:
  /// SCHED_FIFO and memory lock not taken (the loop runs free during runs)". Allocates.
  std::string summary(const RealtimeOptions& requested) const;
};

/// Applies every requested step to the calling thread (memory: the whole process), going on
/// after a failure; also sets the timer slack to 1 ns (helps when SCHED_FIFO is refused).
/// Never throws.
RealtimeReport apply_realtime(const RealtimeOptions& options) noexcept;

}  // namespace hystbench::daemon
