#pragma once
// The fixed-rate loop thread: absolute deadlines (clock_nanosleep, CLOCK_MONOTONIC), optional
// SCHED_FIFO / mlockall / CPU affinity. Per tick: the run's drive (its excitation, then its
// RunDrive) -> limits -> driver write -> driver read -> score -> record and log. Idle ticks ramp
// the output to the driver's safe value through the slew limit and keep reading, so timing
// statistics are kept all the time.
//
// Threads: the loop thread runs tick(); every public method except the constructor, start(),
// step() and shutdown() is for the control thread and is lock-free. step() runs one tick on the
// caller's thread instead (no loop thread, the clock of BenchLoopOptions::clock_ns): tests drive
// the loop deterministically, tick by tick, through the same per-tick path. Runs are handed over as
// whole RunProgram objects (see run_program.hpp); the loop never allocates, locks or throws.
//
// A stage of several axes (the driver's axes() > 1): every tick writes every axis and reads every
// axis at once (write_axes/read_axes), each axis through its own limiter and stuck-sensor
// watch; a run drives its axes (RunProgram::stage_axes), the others hold their safe output. A
// fault on any axis faults the run and puts every axis in its safe state.
//
// Faults (driver error, non-finite or stuck measurement, overrun budget, a limit hit with fatal
// limits): the driver goes to its safe state in the same tick, the run ends with the reason and the
// loop stays in kFault, writing the safe output, until reset_fault().
//
// Clocks (BenchLoopOptions::clock). kWall: every tick waits for its deadline on CLOCK_MONOTONIC,
// sample times are the deadlines and wake-ups, late ticks count as overruns. kSimulated, for a
// plant that follows a virtual clock (the loopback's simulated actuator): time is the tick count
// times the period, and a sample's scheduled and wake-up times are both that virtual time, so logs
// have the same columns and time grid as on the wall clock. During a run the loop ticks without
// sleeping, each tick as soon as the previous one is computed. After a run (and after start) the
// idle first lasts BenchLoopOptions::held_gap_s of virtual time, ticked without sleeping, and a
// run that comes sooner waits for the gap's end: two runs are never closer than the gap, however
// fast the client that sent them. Then the plant's time stands still (no tick) for the grace
// (BenchLoopOptions::idle_grace_s of wall time), and between the runs of one request
// (hold_time_between_runs) until the next run comes: a request's later runs, and a script's next
// request sent within the grace, meet the plant the gap left, whatever the machine's load and
// however long the bench computes. After the grace the idle is paced on the wall clock (and in
// kFault), so an idle daemon does not burn a core and the idle plant evolves at a real one's
// pace. Wake latency is 0 and there are no
// overruns and no overrun faults (lateness means nothing there); execution time per tick is still
// measured on CLOCK_MONOTONIC. No SCHED_FIFO (a free-running FIFO thread would starve the rest of
// the process on its CPU) and no memory lock. A full sample-log ring makes the loop wait for room
// (a short sleep, not real time) instead of dropping the record: every sample is logged.
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "hystbench/daemon/loop/loop_statistics.hpp"
#include "hystbench/daemon/loop/output_history.hpp"
#include "hystbench/daemon/loop/output_limiter.hpp"
#include "hystbench/daemon/loop/reading_lateness.hpp"
#include "hystbench/daemon/loop/realtime.hpp"
#include "hystbench/daemon/loop/run_program.hpp"
#include "hystbench/daemon/loop/scope_tap.hpp"
#include "hystbench/daemon/loop/stuck_sensor_detector.hpp"
#include "hystbench/drivers/driver.hpp"

namespace hystbench::daemon {

/// What the loop's time is (see the header comment).
enum class LoopClock { kWall, kSimulated };
/// "wall" | "simulated".
const char* to_string(LoopClock clock) noexcept;

struct BenchLoopOptions {
  double rate_hz = 10000.0;  ///< [1, 20000]
  LoopClock clock = LoopClock::kWall;
  RealtimeOptions realtime;
  /// Overruns tolerated in one run: overrun number overrun_budget + 1 faults it (0 = the first).
  std::uint64_t overrun_budget = 100;
  OutputLimits limits;
  /// A range or slew limit hit during a run faults it instead of being clamped and counted.
  bool fatal_on_limit = false;
  /// A fresh reading repeated bit for bit after the output has moved a span faults the run (see
  /// stuck_sensor_detector.hpp); resolution_um 0 takes the driver's measurement count.
  StuckSensorOptions stuck_sensor;
  /// Monotonic time [ns] for the sample times and execution figures; null = CLOCK_MONOTONIC
  /// (LoopTimer::now_ns). Must be real-time safe. Used by step() only: the loop thread's
  /// deadlines and figures stay on CLOCK_MONOTONIC.
  std::int64_t (*clock_ns)() noexcept = nullptr;
  /// Simulated clock: the idle after a run [s] of virtual time before the next may start, > 0
  /// (about what a fit between two of identify's segments takes).
  double held_gap_s = 1.0;
  /// Simulated clock: after the gap, time stands still for this long [s] of wall time (a
  /// script's next request comes within it and meets the plant the gap left), and then the
  /// idle is paced on the wall clock; >= 0.
  double idle_grace_s = 2.0;
  /// The axes' names, for the fault reasons of a driver of several ("sensor stuck on axis y:
  /// ..."); an axis without one is named by its index. Unused with one axis.
  std::vector<std::string> axis_names;
  /// A live view's tap: every tap->decimation()-th tick's sample is offered to it (wait-free);
  /// null = none. Must outlive the loop.
  ScopeTap* scope = nullptr;
  /// Ticks of axis 0's output the loop keeps (output_history()), >= 1: 2^21, 8 bytes each, is
  /// 210 s at 10 kHz and 35 min at 1 kHz.
  std::size_t output_history_ticks = std::size_t{1} << 21;
};

class BenchLoop {
 public:
  enum class State : int { kStopped = 0, kIdle, kRunning, kFault };

  /// The driver must be configured and active; it must outlive the loop.
  BenchLoop(drivers::Driver& driver, const BenchLoopOptions& options);
  ~BenchLoop();
  BenchLoop(const BenchLoop&) = delete;
  BenchLoop& operator=(const BenchLoop&) = delete;

  /// Starts the loop thread and returns what its real-time setup achieved (with the simulated
  /// clock: no SCHED_FIFO and no memory lock, whatever options.realtime asks).
  RealtimeReport start();
  /// Ends any run (aborted), drives the safe output, joins the thread. Idempotent.
  void shutdown();
  /// One tick now (the clock's time is both its deadline and its wake-up), on the caller's
  /// thread, for a loop that was not start()ed: idle -> running -> finished exactly as on the
  /// loop thread, without the real-time setup or sleeping. Real-time safe. Ignored while the
  /// loop thread runs.
  void step() noexcept;

  /// Hands a run to the loop. Fails (returns the program back) when a run is active, another
  /// is pending, a finished one has not been taken yet, the loop is in kFault, or the run has
  /// more axes than the driver serves.
  std::unique_ptr<RunProgram> submit(std::unique_ptr<RunProgram> program);
  /// Simulated clock only (ignored on the wall clock and by step()): while on, the idle after
  /// the gap (held_gap_s) does not tick, past the grace too: time stands still until a run is
  /// submitted. The bench holds it from a request's start to its result, so the runs of one
  /// request (identify's segments) see the same plant however long it computes between them.
  void hold_time_between_runs(bool on) noexcept { hold_gaps_.store(on, std::memory_order_release); }
  /// Ends the active run normally at the next tick.
  void request_stop() noexcept { stop_requested_.store(true, std::memory_order_release); }
  /// Safe output at the next tick; the active run ends as aborted (not a fault).
  void request_abort() noexcept { abort_requested_.store(true, std::memory_order_release); }
  /// A finished run (completed, stopped, aborted or faulted), or null.
  std::unique_ptr<RunProgram> take_finished() noexcept;
  /// Leaves kFault for kIdle, waiting up to a second for the loop to acknowledge; false when
  /// not in kFault or the loop did not leave it.
  bool reset_fault() noexcept;
  /// Counts what the control thread waits for: a run finished, a fault, a reset, shutdown.
  std::uint32_t events() const noexcept { return events_.load(std::memory_order_acquire); }
  /// Bumps events(): wakes the control thread's wait_event() for work of its own (the bench
  /// queued a run's preparation). Real-time safe.
  void wake_control() noexcept { signal_event(); }
  /// Blocks until events() differs from `seen` or `timeout` has passed (control thread; the
  /// loop wakes it without a lock). True when it changed.
  bool wait_event(std::uint32_t seen, std::chrono::nanoseconds timeout) const noexcept;
  /// Blocks until done() holds, re-checked on every event, or `timeout` has passed; returns
  /// done() (control thread).
  template <class Done>
  bool wait_for(Done done, std::chrono::nanoseconds timeout) const {
    const auto until = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      const std::uint32_t seen = events();
      if (done()) return true;
      if (!wait_event(seen, until - std::chrono::steady_clock::now())) return done();
    }
  }

  State state() const noexcept { return state_.load(std::memory_order_acquire); }
  /// Why the loop is in kFault (static string; empty otherwise).
  const char* fault_reason() const noexcept {
    return fault_reason_.load(std::memory_order_acquire);
  }
  /// The active run's program (for progress), valid only while state() == kRunning.
  const RunProgram* active() const noexcept { return active_pub_.load(std::memory_order_acquire); }
  /// Timing since start (or the last reset_statistics()).
  LoopStatisticsSnapshot statistics() const noexcept { return stats_.snapshot(); }
  void reset_statistics() noexcept { stats_.request_reset(); }
  /// Axis a's last reading [µm] and output [V] (a < axes()).
  double last_measurement(std::size_t a = 0) const noexcept {
    return last_y_[a].load(std::memory_order_relaxed);
  }
  double last_output(std::size_t a = 0) const noexcept {
    return last_u_[a].load(std::memory_order_relaxed);
  }
  /// The driver's axes, [1, drivers::kMaxAxes].
  std::size_t axes() const noexcept { return axes_; }
  /// Axis 0's output of every tick that exchanged with the driver, the last
  /// options().output_history_ticks of them (see output_history.hpp).
  const OutputHistory& output_history() const noexcept { return output_history_; }
  /// Increments every tick, and every poll while the simulated clock's time stands still: the
  /// watchdog is fed only while it advances.
  std::uint64_t ticks() const noexcept { return ticks_.load(std::memory_order_relaxed); }
  const BenchLoopOptions& options() const noexcept { return options_; }

 private:
  std::int64_t now_ns() const noexcept;
  /// The wall-clock loop: sleeps to each deadline.
  void run_wall();
  /// The simulated-clock loop: free-running ticks during a run, paced ones while idle.
  void run_simulated();
  /// What the simulated clock does next (loop thread; sets defer_pending_).
  enum class SimulatedStep { kFree, kPaced, kStandStill };
  SimulatedStep next_simulated_step() noexcept;
  /// A run is active or waiting to be picked up by the next tick (loop thread).
  bool run_in_play() const noexcept {
    return active_ != nullptr || pending_.load(std::memory_order_acquire) != nullptr;
  }
  void tick(std::int64_t scheduled_ns, std::int64_t wake_ns) noexcept;
  void run_tick(RunProgram& p, std::int64_t scheduled_ns, std::int64_t wake_ns) noexcept;
  // run_tick's stages, in order: drive -> limit -> exchange -> score -> record. Each fills its
  // part of the sample's record. Inline, defined in bench_loop.cpp (their only caller), so that
  // the compiler can keep the tick one function.
  struct TickDrive;
  struct TickExchange;
  /// Per driver axis: what the run's axes asked and got, and the measurements.
  using AxisRecords = std::array<SampleRecord, drivers::kMaxAxes>;
  using AxisValues = std::array<double, drivers::kMaxAxes>;
  /// The output axis a of the run asks for at tick k: its excitation, then its drive's.
  inline TickDrive drive(std::size_t a, RunProgram& p, std::uint64_t k, SampleRecord& rec) noexcept;
  /// Axis a's requested output through its limits, counted, and the model's prediction for it.
  inline OutputLimiter::Applied limit(std::size_t a, RunProgram& p, std::uint64_t k,
                                      double u_request, SampleRecord& rec) noexcept;
  /// Writes every axis's output u and reads every axis's measurement; the run's axes [0, n)
  /// take theirs: the fault, if any, and each reading's age.
  inline TickExchange exchange(RunProgram& p, std::size_t n, std::uint64_t k, const AxisValues& u,
                               bool limited, AxisRecords& rec) noexcept;
  /// A stage's axes' predictions (their own displacements) coupled into the stage's
  /// (RunProgram::coupling), in the records and for each axis's drive. Real-time safe.
  void couple_predictions(RunProgram& p, std::uint64_t k, AxisRecords& rec) noexcept;
  /// Writes u to every axis (write() for one). Real-time safe.
  drivers::DriverStatus write_all(const AxisValues& u) noexcept;
  /// Reads every axis into m (read() for one). Real-time safe.
  drivers::DriverStatus read_all(std::array<drivers::Measurement, drivers::kMaxAxes>& m) noexcept;
  /// Every axis's limiter and last output back at the safe output.
  void reset_outputs() noexcept;
  /// The outputs a tick wrote: every axis's last output, axis 0's into the output history.
  /// Real-time safe.
  void wrote(const AxisValues& u) noexcept;
  /// Adds a sample that did not fault to the run's errors and hands it to the run's drive; true
  /// when the drive's last trial has played.
  static inline bool score(RunProgram& p, std::uint64_t k, const TickDrive& d,
                           const SampleRecord& rec) noexcept;
  /// Keeps axis p's sample in its record and timing, and publishes it as done.
  inline void record(RunProgram& p, std::uint64_t k, const TickDrive& d, std::uint32_t response,
                     std::int64_t wake_latency_ns, const SampleRecord& rec) noexcept;
  void idle_tick() noexcept;
  /// Offers the tick's sample to options_.scope when one is due (loop thread, real-time safe).
  void tap_scope(std::uint64_t tick, std::int64_t scheduled_ns) noexcept;
  /// Pushes the tick's row (a record per axis of the run) to the run's log: a full ring drops it
  /// on the wall clock and waits for room on the simulated clock.
  void log_sample(RunProgram& p, std::span<const SampleRecord> row) noexcept;
  void end_run(RunEnd end, const char* reason) noexcept;
  void fault(const char* reason) noexcept;
  /// Bumps events() and wakes wait_event(): one non-blocking system call.
  void signal_event() noexcept;
  // Simulated clock: waits while the drive awaits its control thread at tick k (RunDrive::awaits).
  void await_drive(const RunDrive& drive, std::uint64_t k) noexcept;

  drivers::Driver& driver_;
  BenchLoopOptions options_;
  std::size_t axes_ = 1;                    // the driver's
  std::vector<OutputLimiter> limiters_;     // per axis
  std::vector<StuckSensorDetector> stuck_;  // per axis
  // Per axis of several, each per-axis fault's reason naming it (built once: the tick only
  // points at them). Empty with one axis, whose reasons are the plain ones.
  enum AxisFault : std::size_t { kOscillates = 0, kNotFinite, kStuck, kAxisFaults };
  std::vector<std::array<std::string, kAxisFaults>> axis_faults_;
  const char* axis_fault(std::size_t a, AxisFault f) const noexcept;
  LoopStatistics stats_;
  std::thread thread_;
  std::atomic<bool> quit_{false};
  std::atomic<State> state_{State::kStopped};
  std::atomic<const char*> fault_reason_{""};
  std::atomic<RunProgram*> pending_{nullptr};
  std::atomic<RunProgram*> finished_{nullptr};
  std::atomic<const RunProgram*> active_pub_{nullptr};
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> abort_requested_{false};
  std::atomic<bool> reset_requested_{false};
  std::atomic<bool> hold_gaps_{false};
  std::array<std::atomic<double>, drivers::kMaxAxes> last_y_{};  // per axis
  std::array<std::atomic<double>, drivers::kMaxAxes> last_u_{};
  std::atomic<std::uint64_t> ticks_{0};
  std::atomic<std::uint32_t> events_{0};
  RealtimeReport realtime_report_;

  // Loop-thread state.
  RunProgram* active_ = nullptr;
  std::int64_t run_start_ns_ = 0;
  // Per axis, the last tick's reading for the feedback; NaN after a stale one and after a
  // stall (it holds). With how late it answered (ReadingLateness): the feedback compares it with
  // the reference of then.
  AxisValues y_prev_{};
  std::array<std::uint64_t, drivers::kMaxAxes> y_prev_late_{};
  std::array<ReadingLateness, drivers::kMaxAxes> lateness_{};
  // Per axis, the last tick's reference for the scope; NaN while none is driven.
  AxisValues last_yr_{};
  double dt_ = 1e-4;
  std::int64_t period_ns_ = 100000;
  bool overran_ = false;
  bool stepped_ = false;  // driven by step(): the injected clock applies
  bool simulated_ = false;
  // Simulated clock: idle ticks since the last run ended, the held gap's length in ticks, and
  // whether a pending run waits for the gap to be full.
  std::uint64_t idle_ticks_ = 0;
  std::uint64_t held_gap_ticks_ = 1;
  bool defer_pending_ = false;
  // Simulated clock: the grace after the gap [ns of CLOCK_MONOTONIC], and when this idle's ends
  // (-1 until its gap is full).
  std::int64_t idle_grace_ns_ = 0;
  std::int64_t grace_end_ns_ = -1;
  std::int64_t exec_start_ns_ = 0;  // CLOCK_MONOTONIC (or step()'s clock) when this tick began
  OutputHistory output_history_;
};

}  // namespace hystbench::daemon
