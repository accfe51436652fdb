#include "hystbench/daemon/loop/bench_loop.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <thread>

#include "hystbench/daemon/loop/loop_timer.hpp"
#include "loop/details/futex.hpp"

namespace hystbench::daemon {

namespace {
/// The configured stuck-sensor options; the driver's count size when none is configured.
StuckSensorOptions stuck_options(StuckSensorOptions o, const drivers::Driver& driver) {
  if (o.resolution_um <= 0.0) o.resolution_um = driver.measurement_resolution_um();
  return o;
}
}  // namespace

const char* to_string(LoopClock clock) noexcept {
  return clock == LoopClock::kSimulated ? "simulated" : "wall";
}

namespace {

// What each per-axis fault says, after "on axis NAME: " on a driver of several.
constexpr std::array<const char*, 3> kAxisFaultWhat = {
    "the feedback loop oscillates (a growing or sustained oscillation of the error)",
    "measurement is not a finite number",
    "sensor stuck: the same reading while the output moved (loop.stuck_sensor_ms)"};

}  // namespace

BenchLoop::BenchLoop(drivers::Driver& driver, const BenchLoopOptions& options)
    : driver_(driver),
      options_(options),
      axes_(std::clamp<std::size_t>(driver.axes(), 1, drivers::kMaxAxes)),
      limiters_(axes_, OutputLimiter(options.limits, 1.0 / options.rate_hz)),
      stuck_(axes_, StuckSensorDetector(stuck_options(options.stuck_sensor, driver))),
      dt_(1.0 / options.rate_hz),
      period_ns_(static_cast<std::int64_t>(std::llround(1e9 / options.rate_hz))),
      simulated_(options.clock == LoopClock::kSimulated),
      held_gap_ticks_(std::max<std::uint64_t>(
          1, static_cast<std::uint64_t>(std::llround(options.held_gap_s * options.rate_hz)))),
      idle_grace_ns_(
          static_cast<std::int64_t>(std::llround(std::max(0.0, options.idle_grace_s) * 1e9))),
      output_history_(std::max<std::size_t>(1, options.output_history_ticks)) {
  if (axes_ > 1) {
    axis_faults_.resize(axes_);
    for (std::size_t a = 0; a < axes_; ++a) {
      const std::string name =
          a < options_.axis_names.size() ? options_.axis_names[a] : std::to_string(a);
      for (std::size_t f = 0; f < kAxisFaults; ++f) {
        axis_faults_[a][f] = "on axis " + name + ": " + kAxisFaultWhat[f];
      }
    }
  }
  reset_outputs();
}

void BenchLoop::reset_outputs() noexcept {
  for (std::size_t a = 0; a < axes_; ++a) {
    limiters_[a].reset(driver_.safe_output_v());
    last_u_[a].store(driver_.safe_output_v(), std::memory_order_relaxed);
  }
}

void BenchLoop::wrote(const AxisValues& u) noexcept {
  for (std::size_t a = 0; a < axes_; ++a) last_u_[a].store(u[a], std::memory_order_relaxed);
  output_history_.push(u[0]);
}

drivers::DriverStatus BenchLoop::write_all(const AxisValues& u) noexcept {
  return axes_ == 1 ? driver_.write(u[0]) : driver_.write_axes(std::span(u).first(axes_));
}

drivers::DriverStatus BenchLoop::read_all(
    std::array<drivers::Measurement, drivers::kMaxAxes>& m) noexcept {
  return axes_ == 1 ? driver_.read(m[0]) : driver_.read_axes(std::span(m).first(axes_));
}

BenchLoop::~BenchLoop() {
  shutdown();
  delete finished_.exchange(nullptr);
}

RealtimeReport BenchLoop::start() {
  if (thread_.joinable()) return realtime_report_;
  std::promise<RealtimeReport> ready;
  auto report = ready.get_future();
  state_.store(State::kIdle, std::memory_order_release);
  thread_ = std::thread([this, &ready] {
    RealtimeOptions rt = options_.realtime;
    if (simulated_) {
      // A free-running SCHED_FIFO thread would starve the process's other threads on its CPU.
      rt.fifo = false;
      rt.lock_memory = false;
    }
    realtime_report_ = apply_realtime(rt);
    realtime_report_.simulated_clock = simulated_;
    prefault_stack();
    ready.set_value(realtime_report_);
    if (simulated_) {
      run_simulated();
    } else {
      run_wall();
    }
    if (active_ != nullptr) end_run(RunEnd::kAborted, "daemon shutting down");
    driver_.safe_state();
  });
  return report.get();
}

void BenchLoop::shutdown() {
  if (!thread_.joinable()) return;
  quit_.store(true, std::memory_order_release);
  thread_.join();
  driver_.safe_state();
  state_.store(State::kStopped, std::memory_order_release);
  // A program the loop never picked up is dropped; a finished one stays for take_finished().
  delete pending_.exchange(nullptr);
  signal_event();
}

std::unique_ptr<RunProgram> BenchLoop::submit(std::unique_ptr<RunProgram> program) {
  if (state() != State::kIdle || finished_.load(std::memory_order_acquire) != nullptr ||
      program->axes() > axes_) {
    return program;
  }
  for (std::size_t a = 0; a < program->axes(); ++a) {
    RunProgram& p = program->axis(a);
    // Beyond its excitation a run needs a drive (RunDrive).
    if (!p.drive && p.total_samples > p.excitation.size()) return program;
    p.dt_s = dt_;
    if (p.drive) {
      p.drive->configure(DriveSetup{dt_, options_.limits.u_min, options_.limits.u_max,
                                    static_cast<std::uint64_t>(p.excitation.size())});
    }
  }
  RunProgram* expected = nullptr;
  RunProgram* raw = program.get();
  stop_requested_.store(false, std::memory_order_relaxed);
  abort_requested_.store(false, std::memory_order_relaxed);
  if (!pending_.compare_exchange_strong(expected, raw, std::memory_order_acq_rel)) return program;
  (void)program.release();  // pending_ owns it now; the loop hands it back through finished_
  return nullptr;
}

std::unique_ptr<RunProgram> BenchLoop::take_finished() noexcept {
  return std::unique_ptr<RunProgram>(finished_.exchange(nullptr, std::memory_order_acq_rel));
}

bool BenchLoop::reset_fault() noexcept {
  if (state() != State::kFault) return false;
  reset_requested_.store(true, std::memory_order_release);
  // The loop acknowledges within a tick; wait so the caller sees the new state.
  return wait_for([this] { return state() != State::kFault; }, std::chrono::seconds(1));
}

bool BenchLoop::wait_event(std::uint32_t seen, std::chrono::nanoseconds timeout) const noexcept {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (events() == seen) {
    const auto left = until - std::chrono::steady_clock::now();
    if (left <= left.zero()) return false;
    details::futex_wait(events_, seen, left);
  }
  return true;
}

void BenchLoop::signal_event() noexcept {
  events_.fetch_add(1, std::memory_order_acq_rel);
  details::futex_wake_all(events_);
}

std::int64_t BenchLoop::now_ns() const noexcept {
  return stepped_ && options_.clock_ns != nullptr ? options_.clock_ns() : LoopTimer::now_ns();
}

void BenchLoop::step() noexcept {
  if (thread_.joinable()) return;
  stepped_ = true;
  if (state() == State::kStopped) state_.store(State::kIdle, std::memory_order_release);
  const std::int64_t t = now_ns();
  overran_ = false;
  exec_start_ns_ = t;
  tick(t, t);
  stats_.record(0, now_ns() - t, false, 0);
}

void BenchLoop::run_wall() {
  LoopTimer timer{std::chrono::nanoseconds(period_ns_)};
  timer.start();
  while (!quit_.load(std::memory_order_acquire)) {
    const LoopTimer::Tick t = timer.wait();
    // A tick that wakes after its successor's deadline (the previous work or the scheduler
    // made it late by a period or more, so deadlines were skipped) counts as an overrun.
    overran_ = t.skipped > 0;
    exec_start_ns_ = t.wake_ns;
    tick(t.scheduled_ns, t.wake_ns);
    const std::int64_t done = LoopTimer::now_ns();
    stats_.record(t.latency_ns(), done - t.wake_ns, overran_ || timer.overran(t, done), t.skipped);
  }
}

void BenchLoop::run_simulated() {
  LoopTimer timer{std::chrono::nanoseconds(period_ns_)};
  bool paced = false;
  std::int64_t virtual_ns = 0;  // tick count x period
  overran_ = false;
  while (!quit_.load(std::memory_order_acquire)) {
    switch (next_simulated_step()) {
      case SimulatedStep::kFree:
        paced = false;  // the next tick as soon as this one is computed
        break;
      case SimulatedStep::kPaced:
        if (!paced) timer.start();  // idle again: paced from now on, whatever the run took
        paced = true;
        (void)timer.wait();
        // A run may have come, and the hold with it, while the loop slept: decided again.
        if (next_simulated_step() == SimulatedStep::kStandStill) continue;
        break;
      case SimulatedStep::kStandStill:
        ticks_.fetch_add(1, std::memory_order_relaxed);  // alive, for the watchdog
        std::this_thread::sleep_for(std::chrono::microseconds(200));
        continue;
    }
    exec_start_ns_ = LoopTimer::now_ns();
    tick(virtual_ns, virtual_ns);
    stats_.record(0, LoopTimer::now_ns() - exec_start_ns_, false, 0);
    virtual_ns += period_ns_;
  }
}

BenchLoop::SimulatedStep BenchLoop::next_simulated_step() noexcept {
  defer_pending_ = false;
  if (state() == State::kFault) return SimulatedStep::kPaced;
  if (active_ != nullptr) return SimulatedStep::kFree;
  if (idle_ticks_ < held_gap_ticks_) {
    defer_pending_ = true;  // the gap first, however early the next run came
    return SimulatedStep::kFree;
  }
  const bool pending = pending_.load(std::memory_order_acquire) != nullptr;
  // The grace: the next request of a script that sends it within this wall time after the gap
  // meets the plant the gap left, whatever the machine's load.
  const std::int64_t now = LoopTimer::now_ns();
  if (grace_end_ns_ < 0) grace_end_ns_ = now + idle_grace_ns_;
  if (!hold_gaps_.load(std::memory_order_acquire) && now >= grace_end_ns_) {
    return pending ? SimulatedStep::kFree : SimulatedStep::kPaced;
  }
  if (pending || abort_requested_.load(std::memory_order_acquire) ||
      reset_requested_.load(std::memory_order_acquire)) {
    return SimulatedStep::kFree;
  }
  return SimulatedStep::kStandStill;
}

void BenchLoop::log_sample(RunProgram& p, std::span<const SampleRecord> row) noexcept {
  if (!p.log) return;
  if (!simulated_ || p.log->row_records() != row.size()) {
    if (!p.log->push_row(row)) ++p.counters.log_drops;
    return;
  }
  // Back-pressure: virtual time waits for the writer, nothing is dropped. Only a closed log or
  // a shutting-down daemon gives up (push_row() then counts the drop).
  while (!p.log->try_push_row(row)) {
    if (p.log->closed() || quit_.load(std::memory_order_acquire)) {
      (void)p.log->push_row(row);
      ++p.counters.log_drops;
      return;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

void BenchLoop::tick(std::int64_t scheduled_ns, std::int64_t wake_ns) noexcept {
  const std::uint64_t tick_number = ticks_.fetch_add(1, std::memory_order_relaxed);
  if (options_.scope != nullptr) tap_scope(tick_number, scheduled_ns);
  if (reset_requested_.exchange(false, std::memory_order_acq_rel) && state() == State::kFault) {
    fault_reason_.store("", std::memory_order_release);
    state_.store(State::kIdle, std::memory_order_release);
    signal_event();
  }
  if (state() == State::kFault) {
    driver_.safe_state();
    output_history_.push(driver_.safe_output_v());
    std::array<drivers::Measurement, drivers::kMaxAxes> m{};
    if (read_all(m) == drivers::DriverStatus::kOk) {
      for (std::size_t a = 0; a < axes_; ++a) last_y_[a].store(m[a].position_um);
    }
    return;
  }
  if (active_ == nullptr && !defer_pending_) {
    RunProgram* p = pending_.exchange(nullptr, std::memory_order_acq_rel);
    if (p != nullptr) {
      active_ = p;
      idle_ticks_ = 0;
      grace_end_ns_ = -1;
      for (std::size_t a = 0; a < axes_; ++a) {
        stuck_[a].reset(options_.stuck_sensor.latency_ticks + p->response_delay_ticks);
        lateness_[a].reset();
        y_prev_late_[a] = 0;
      }
      driver_.set_run_active(true);
      run_start_ns_ = scheduled_ns;
      active_pub_.store(p, std::memory_order_release);
      state_.store(State::kRunning, std::memory_order_release);
    }
  }
  if (abort_requested_.exchange(false, std::memory_order_acq_rel)) {
    // Safe output now, not ramped; a run ends as aborted.
    driver_.safe_state();
    reset_outputs();
    output_history_.push(driver_.safe_output_v());
    if (active_ != nullptr) end_run(RunEnd::kAborted, "aborted by request");
    return;
  }
  if (active_ != nullptr) {
    run_tick(*active_, scheduled_ns, wake_ns);
  } else {
    idle_tick();
  }
}

void BenchLoop::tap_scope(std::uint64_t tick, std::int64_t scheduled_ns) noexcept {
  // The previous tick's exchange: its output, the reading it got and the reference it drove.
  if (!options_.scope->due(tick)) return;
  ScopeSample s;
  s.tick = tick;
  s.time_ns = scheduled_ns;
  s.axes = static_cast<std::uint32_t>(axes_);
  s.running = active_ != nullptr;
  for (std::size_t a = 0; a < axes_; ++a) {
    s.y[a] = last_y_[a].load(std::memory_order_relaxed);
    s.u[a] = last_u_[a].load(std::memory_order_relaxed);
    s.yr[a] = s.running ? last_yr_[a] : std::numeric_limits<double>::quiet_NaN();
  }
  options_.scope->offer(s);
}

void BenchLoop::idle_tick() noexcept {
  ++idle_ticks_;
  AxisValues u{};
  for (std::size_t a = 0; a < axes_; ++a) u[a] = limiters_[a].apply(driver_.safe_output_v()).u;
  if (write_all(u) != drivers::DriverStatus::kOk) {
    fault("driver write failed while idle");
    return;
  }
  wrote(u);
  std::array<drivers::Measurement, drivers::kMaxAxes> m{};
  const auto st = read_all(m);
  if (st == drivers::DriverStatus::kOk || st == drivers::DriverStatus::kStale) {
    for (std::size_t a = 0; a < axes_; ++a) {
      last_y_[a].store(m[a].position_um, std::memory_order_relaxed);
      y_prev_[a] = m[a].position_um;
    }
  } else {
    fault("driver read failed while idle");
  }
}

/// What the drive stage asks of the output, for the stages after it.
struct BenchLoop::TickDrive {
  double y_ref = std::numeric_limits<double>::quiet_NaN();  ///< NaN: no reference at this tick
  double u_request = 0.0;                                   ///< the output asked for, unlimited
  bool trial_ends = false;  ///< the tick ends a trial the control thread waits for
};

/// What the exchange with the driver leaves for the stages after it.
struct BenchLoop::TickExchange {
  const char* failure = nullptr;  ///< why the run faults at this tick; null when it does not
  /// Per axis, the fresh reading's response_ticks.
  std::array<std::uint32_t, drivers::kMaxAxes> response{};
  TickExchange() { response.fill(RunRecords::kNoFreshReading); }
};

void BenchLoop::run_tick(RunProgram& p, std::int64_t scheduled_ns, std::int64_t wake_ns) noexcept {
  const std::uint64_t k = p.done.load(std::memory_order_relaxed);
  const std::size_t n = p.axes();  // submit() refused more than the driver's
  AxisRecords rec{};
  std::array<TickDrive, drivers::kMaxAxes> d{};
  AxisValues u{};
  bool limited = false;
  for (std::size_t a = 0; a < axes_; ++a) {
    if (a >= n) {  // an axis the run does not drive holds its safe output
      u[a] = limiters_[a].apply(driver_.safe_output_v()).u;
      continue;
    }
    RunProgram& pa = p.axis(a);
    rec[a].index = k;
    rec[a].scheduled_ns = scheduled_ns - run_start_ns_;
    rec[a].wake_ns = wake_ns - run_start_ns_;
    if (overran_) {
      rec[a].flags |= kSampleOverrun;
      ++pa.counters.overruns;
    }
    d[a] = drive(a, pa, k, rec[a]);
    last_yr_[a] = d[a].y_ref;
    const OutputLimiter::Applied lim = limit(a, pa, k, d[a].u_request, rec[a]);
    u[a] = lim.u;
    limited = limited || lim.clamped || lim.slew_limited;
  }
  if (p.coupling && n == p.coupling->axes()) couple_predictions(p, k, rec);
  TickExchange x = exchange(p, n, k, u, limited, rec);
  for (std::size_t a = 0; a < n && x.failure == nullptr; ++a) {
    RunProgram& pa = p.axis(a);
    if (pa.oscillation && k >= pa.feedback_from && std::isfinite(d[a].y_ref) &&
        pa.oscillation->update(d[a].y_ref - rec[a].y_measured, k)) {
      x.failure = axis_fault(a, kOscillates);
      rec[a].flags |= kSampleFault;
    }
  }
  bool last_trial_played = false;
  for (std::size_t a = 0; a < n && x.failure == nullptr; ++a) {
    const bool played = score(p.axis(a), k, d[a], rec[a]);
    if (a == 0) last_trial_played = played;
  }
  rec[0].exec_ns = now_ns() - exec_start_ns_;
  for (std::size_t a = 0; a < n; ++a) {
    rec[a].exec_ns = rec[0].exec_ns;
    if (!std::isfinite(rec[a].reference)) {
      // No reference on an open-loop tick: the log's yr holds what the model expects of the
      // drive, flagged, so that no column is left empty (the run's records keep NaN).
      rec[a].flags |= kSampleOpenLoop;
      rec[a].reference = rec[a].y_model;
    }
    record(p.axis(a), k, d[a], x.response[a], wake_ns - scheduled_ns, rec[a]);
  }
  log_sample(p, std::span<const SampleRecord>(rec).first(n));

  if (x.failure != nullptr) {
    fault(x.failure);
  } else if (k + 1 >= p.total_samples || last_trial_played) {
    end_run(RunEnd::kCompleted,
            last_trial_played ? "its last trial played" : "every planned sample played");
  } else if (stop_requested_.exchange(false, std::memory_order_acq_rel)) {
    end_run(RunEnd::kStopped, "stopped by request");
  }
}

BenchLoop::TickDrive BenchLoop::drive(std::size_t a, RunProgram& p, std::uint64_t k,
                                      SampleRecord& rec) noexcept {
  TickDrive d;
  if (k < p.excitation.size()) {
    // The open-loop drive: identify's, excite's and frf's whole run, track's sweep.
    d.u_request = p.excitation[k];
    rec.u_ff = d.u_request;
  } else {
    if (simulated_) await_drive(*p.drive, k);
    const DriveCommand c =
        p.drive->update(DriveInput{k, y_prev_[a], k >= p.feedback_from, y_prev_late_[a]});
    d.y_ref = c.y_ref;
    d.u_request = c.u;
    d.trial_ends = c.trial_ends;
    rec.u_ff = c.u_ff;
    rec.u_fb = c.u_fb;
    rec.flags |= c.flags;
    if ((c.flags & kSampleReferenceLimited) != 0U) ++p.counters.reference_clips;
  }
  rec.reference = d.y_ref;
  return d;
}

OutputLimiter::Applied BenchLoop::limit(std::size_t a, RunProgram& p, std::uint64_t k,
                                        double u_request, SampleRecord& rec) noexcept {
  const OutputLimiter::Applied lim = limiters_[a].apply(u_request);
  if (p.drive) p.drive->limited(lim.direction);
  if (lim.clamped) {
    rec.flags |= kSampleOutputClamped;
    ++p.counters.clamps;
  }
  if (lim.slew_limited) {
    rec.flags |= kSampleSlewLimited;
    ++p.counters.slew_limits;
  }
  rec.u_out = lim.u;
  if (p.model) {
    rec.y_model = p.model->step(lim.u);
    if (p.drive) p.drive->predicted(k, rec.y_model);
  }
  return lim;
}

void BenchLoop::couple_predictions(RunProgram& p, std::uint64_t k, AxisRecords& rec) noexcept {
  AxisValues own{}, stage{};
  const std::size_t n = p.axes();
  for (std::size_t a = 0; a < n; ++a) {
    if (!p.axis(a).model) return;  // an axis without a prediction: none is coupled
    own[a] = rec[a].y_model;
  }
  p.coupling->couple(std::span(own).first(n), std::span(stage).first(n));
  for (std::size_t a = 0; a < n; ++a) {
    rec[a].y_model = stage[a];
    if (p.axis(a).drive) p.axis(a).drive->predicted(k, stage[a]);
  }
}

BenchLoop::TickExchange BenchLoop::exchange(RunProgram& p, std::size_t n, std::uint64_t k,
                                            const AxisValues& u, bool limited,
                                            AxisRecords& rec) noexcept {
  TickExchange x;
  if (limited && options_.fatal_on_limit) {
    x.failure = "output limit reached (limits.fatal_on_limit)";
  } else if (write_all(u) != drivers::DriverStatus::kOk) {
    x.failure = "driver write failed";
  } else {
    wrote(u);
    std::array<drivers::Measurement, drivers::kMaxAxes> m{};
    const auto st = read_all(m);
    std::array<bool, drivers::kMaxAxes> after_stall{};  // the feedback holds on this reading
    if (st != drivers::DriverStatus::kOk && st != drivers::DriverStatus::kStale) {
      x.failure =
          st == drivers::DriverStatus::kTimeout ? "driver read timed out" : "driver read failed";
    }
    for (std::size_t a = 0; a < n; ++a) {
      RunProgram& pa = p.axis(a);
      if (st == drivers::DriverStatus::kStale) {
        rec[a].flags |= kSampleStale;
        ++pa.counters.stale_reads;
        stuck_[a].stale(u[a]);
        lateness_[a].stale();
      }
      if (x.failure == nullptr && !std::isfinite(m[a].position_um)) {
        x.failure = axis_fault(a, kNotFinite);
      } else if (x.failure == nullptr && st == drivers::DriverStatus::kOk &&
                 stuck_[a].update(u[a], m[a].position_um, m[a].response_ticks)) {
        x.failure = axis_fault(a, kStuck);
      }
      rec[a].y_measured = m[a].position_um;
      if (st == drivers::DriverStatus::kOk) {
        x.response[a] = static_cast<std::uint32_t>(
            std::min<std::uint64_t>(m[a].response_ticks, RunRecords::kNoFreshReading - 1));
        const ReadingLateness::Fresh f = lateness_[a].fresh(x.response[a]);
        y_prev_late_[a] = f.late_ticks;
        after_stall[a] = f.hold;
      }
    }
    if (x.failure == nullptr) {
      for (std::size_t a = 0; a < axes_; ++a) {
        // A stale reading is the last fresh one again: the feedback must not integrate an error
        // that only the reading's age makes. It holds until the next fresh one, and over the
        // fresh ones that follow a stall (ReadingLateness).
        y_prev_[a] = st == drivers::DriverStatus::kOk && !after_stall[a]
                         ? m[a].position_um
                         : std::numeric_limits<double>::quiet_NaN();
        last_y_[a].store(m[a].position_um, std::memory_order_relaxed);
        if (a < n && st == drivers::DriverStatus::kOk && p.axis(a).drive) {
          p.axis(a).drive->measured(k, m[a]);
        }
      }
    }
  }
  if (x.failure == nullptr && p.counters.overruns > options_.overrun_budget) {
    x.failure = "overrun budget exceeded (loop.overrun_budget)";
  }
  if (x.failure != nullptr) {
    for (std::size_t a = 0; a < n; ++a) rec[a].flags |= kSampleFault;
  }
  return x;
}

bool BenchLoop::score(RunProgram& p, std::uint64_t k, const TickDrive& d,
                      const SampleRecord& rec) noexcept {
  if (k >= p.metrics_from && !std::isnan(d.y_ref)) {
    p.error.add(rec.y_measured - d.y_ref, k);
  }
  if (k >= p.metrics_from && k >= p.model_metrics_from && p.model) {
    p.model_error.add(rec.y_measured - rec.y_model, k);
  }
  if (!p.drive) return false;
  const DriveScore s = p.drive->scored(k, d.y_ref, rec.y_measured, rec.u_ff);
  if (s.scored_from < p.metrics_from) {
    // A learned drive's lead-in that ended early moves the scored part (and the feedback's
    // start, where it began with it) up.
    if (p.feedback_from == p.metrics_from) p.feedback_from = s.scored_from;
    p.metrics_from = s.scored_from;
  }
  return s.last_trial;
}

void BenchLoop::record(RunProgram& p, std::uint64_t k, const TickDrive& d, std::uint32_t response,
                       std::int64_t wake_latency_ns, const SampleRecord& rec) noexcept {
  if (p.records.count < p.records.capacity && k >= p.metrics_from) {
    p.records.u[p.records.count] = rec.u_out;
    p.records.y[p.records.count] = rec.y_measured;
    p.records.yr[p.records.count] = d.y_ref;
    if (!p.records.response.empty()) p.records.response[p.records.count] = response;
    ++p.records.count;
  }
  p.stats.record(wake_latency_ns, rec.exec_ns, overran_);
  p.done.store(k + 1, std::memory_order_release);
  if (d.trial_ends) signal_event();  // a trial for the control thread
}

void BenchLoop::await_drive(const RunDrive& drive, std::uint64_t k) noexcept {
  // Virtual time waits for the control thread, as for the log writer (a learner: each period
  // after a trial plays the drive learned from it). A stop, an abort or a shutdown ends the wait.
  while (drive.awaits(k) && !quit_.load(std::memory_order_acquire) &&
         !stop_requested_.load(std::memory_order_acquire) &&
         !abort_requested_.load(std::memory_order_acquire)) {
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
}

void BenchLoop::end_run(RunEnd end, const char* reason) noexcept {
  RunProgram* p = active_;
  if (p == nullptr) return;
  for (std::size_t a = 0; a < p->axes(); ++a) {
    p->axis(a).end = end;
    p->axis(a).end_reason = reason;
  }
  active_ = nullptr;
  driver_.set_run_active(false);
  active_pub_.store(nullptr, std::memory_order_release);
  if (end != RunEnd::kFault) state_.store(State::kIdle, std::memory_order_release);
  finished_.store(p, std::memory_order_release);
  signal_event();
}

const char* BenchLoop::axis_fault(std::size_t a, AxisFault f) const noexcept {
  if (a < axis_faults_.size()) return axis_faults_[a][f].c_str();
  return kAxisFaultWhat[f];
}

void BenchLoop::fault(const char* reason) noexcept {
  driver_.safe_state();
  reset_outputs();
  fault_reason_.store(reason, std::memory_order_release);
  state_.store(State::kFault, std::memory_order_release);
  end_run(RunEnd::kFault, reason);
  signal_event();
}

}  // namespace hystbench::daemon
