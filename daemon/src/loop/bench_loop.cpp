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

BenchLoop::BenchLoop(drivers::Driver& driver, BenchLoopOptions options)
    : driver_(driver),
      options_(options),
      limiter_(options.limits, 1.0 / options.rate_hz),
      stuck_(stuck_options(options.stuck_sensor, driver)),
      dt_(1.0 / options.rate_hz),
      period_ns_(static_cast<std::int64_t>(std::llround(1e9 / options.rate_hz))),
      simulated_(options.clock == LoopClock::kSimulated),
      held_gap_ticks_(std::max<std::uint64_t>(
          1, static_cast<std::uint64_t>(std::llround(options.held_gap_s * options.rate_hz)))) {
  limiter_.reset(driver_.safe_output_v());
  last_u_.store(driver_.safe_output_v());
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
  if (state() != State::kIdle || finished_.load(std::memory_order_acquire) != nullptr) {
    return program;
  }
  // The targets ahead, for an inverse that uses them. Not yet with a dynamics preview, whose
  // target is already computed from the reference ahead: fed both, the rate inverse tracked worse.
  if (program->compensator && !program->preview) {
    program->targets.allocate(program->compensator->preview_samples());
  }
  if (program->learned_twin && !program->preview) {
    program->twin_targets.allocate(program->learned_twin->preview_samples());
  }
  program->dt_s = dt_;
  // The feedback's integral holds while the drive sits at a bound of the output range.
  if (program->compensator) {
    program->compensator->set_drive_range(options_.limits.u_min, options_.limits.u_max);
  }
  if (program->learned_twin) {
    program->learned_twin->set_drive_range(options_.limits.u_min, options_.limits.u_max);
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
  const bool pending = pending_.load(std::memory_order_acquire) != nullptr;
  if (!hold_gaps_.load(std::memory_order_acquire)) {
    return pending ? SimulatedStep::kFree : SimulatedStep::kPaced;
  }
  if (idle_ticks_ < held_gap_ticks_) {
    defer_pending_ = true;  // the gap first, however early the next run came
    return SimulatedStep::kFree;
  }
  if (pending || abort_requested_.load(std::memory_order_acquire) ||
      reset_requested_.load(std::memory_order_acquire)) {
    return SimulatedStep::kFree;
  }
  return SimulatedStep::kStandStill;
}

void BenchLoop::log_sample(RunProgram& p, const SampleRecord& rec) noexcept {
  if (!p.log) return;
  if (!simulated_) {
    if (!p.log->push(rec)) ++p.counters.log_drops;
    return;
  }
  // Back-pressure: virtual time waits for the writer, nothing is dropped. Only a closed log or
  // a shutting-down daemon gives up (push() then counts the drop).
  while (!p.log->try_push(rec)) {
    if (p.log->closed() || quit_.load(std::memory_order_acquire)) {
      (void)p.log->push(rec);
      ++p.counters.log_drops;
      return;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

void BenchLoop::tick(std::int64_t scheduled_ns, std::int64_t wake_ns) noexcept {
  ticks_.fetch_add(1, std::memory_order_relaxed);
  if (reset_requested_.exchange(false, std::memory_order_acq_rel) && state() == State::kFault) {
    fault_reason_.store("", std::memory_order_release);
    state_.store(State::kIdle, std::memory_order_release);
    signal_event();
  }
  if (state() == State::kFault) {
    driver_.safe_state();
    drivers::Measurement m;
    if (driver_.read(m) == drivers::DriverStatus::kOk) last_y_.store(m.position_um);
    return;
  }
  if (active_ == nullptr && !defer_pending_) {
    RunProgram* p = pending_.exchange(nullptr, std::memory_order_acq_rel);
    if (p != nullptr) {
      active_ = p;
      idle_ticks_ = 0;
      stuck_.reset(options_.stuck_sensor.latency_ticks + p->response_delay_ticks);
      driver_.set_run_active(true);
      run_start_ns_ = scheduled_ns;
      active_pub_.store(p, std::memory_order_release);
      state_.store(State::kRunning, std::memory_order_release);
    }
  }
  if (abort_requested_.exchange(false, std::memory_order_acq_rel)) {
    // Safe output now, not ramped; a run ends as aborted.
    driver_.safe_state();
    limiter_.reset(driver_.safe_output_v());
    last_u_.store(driver_.safe_output_v());
    if (active_ != nullptr) end_run(RunEnd::kAborted, "aborted by request");
    return;
  }
  if (active_ != nullptr) {
    run_tick(*active_, scheduled_ns, wake_ns);
  } else {
    idle_tick();
  }
}

void BenchLoop::idle_tick() noexcept {
  ++idle_ticks_;
  const auto lim = limiter_.apply(driver_.safe_output_v());
  if (driver_.write(lim.u) != drivers::DriverStatus::kOk) {
    fault("driver write failed while idle");
    return;
  }
  last_u_.store(lim.u, std::memory_order_relaxed);
  drivers::Measurement m;
  const auto st = driver_.read(m);
  if (st == drivers::DriverStatus::kOk || st == drivers::DriverStatus::kStale) {
    last_y_.store(m.position_um, std::memory_order_relaxed);
    y_prev_ = m.position_um;
  } else {
    fault("driver read failed while idle");
  }
}

/// What the drive stage asks of the output, for the stages after it.
struct BenchLoop::TickDrive {
  double y_ref = std::numeric_limits<double>::quiet_NaN();  ///< NaN: no reference at this tick
  double u_request = 0.0;                                   ///< the output asked for, unlimited
  double u_compensator = 0.0;  ///< the compensator's feedforward, for a learning run
  std::size_t phase = 0;       ///< the learning trial's phase
  bool learning = false;       ///< the tick belongs to a learning run's trials, at this phase
  bool lead_in = false;        ///< a drive learned before plays the period before trial 0
};

/// What the exchange with the driver leaves for the stages after it.
struct BenchLoop::TickExchange {
  const char* failure = nullptr;  ///< why the run faults at this tick; null when it does not
  std::uint32_t response = RunRecords::kNoFreshReading;  ///< the fresh reading's response_ticks
};

namespace {
/// Adds the tare's sample: a fresh reading on the open-loop prefix less the model's prediction
/// for the output it answers (the reading answers the output of response_ticks ago, less the
/// exchange latency the model's delay holds).
void add_tare_sample(RunProgram& p, std::uint64_t k, const drivers::Measurement& m) noexcept {
  const std::uint64_t lag = m.response_ticks > p.tare.model_exchange_ticks
                                ? m.response_ticks - p.tare.model_exchange_ticks
                                : 0;
  if (p.model && k >= p.tare.from && k < p.excitation.size() && lag < TareWindow::kHistory &&
      lag <= k) {
    p.tare.sum += m.position_um - p.tare.y_model_history[(k - lag) % TareWindow::kHistory];
    ++p.tare.samples;
  }
}
}  // namespace

void BenchLoop::run_tick(RunProgram& p, std::int64_t scheduled_ns, std::int64_t wake_ns) noexcept {
  const std::uint64_t k = p.done.load(std::memory_order_relaxed);
  SampleRecord rec;
  rec.index = k;
  rec.scheduled_ns = scheduled_ns - run_start_ns_;
  rec.wake_ns = wake_ns - run_start_ns_;
  if (overran_) {
    rec.flags |= kSampleOverrun;
    ++p.counters.overruns;
  }
  const TickDrive d = drive(p, k, rec);
  const OutputLimiter::Applied lim = limit(p, k, d.u_request, rec);
  TickExchange x = exchange(p, k, lim, rec);
  if (x.failure == nullptr && p.oscillation && k >= p.feedback_from && std::isfinite(d.y_ref) &&
      p.oscillation->update(d.y_ref - rec.y_measured, k)) {
    x.failure = "the feedback loop oscillates (a growing or sustained oscillation of the error)";
    rec.flags |= kSampleFault;
  }
  const bool last_trial_played = x.failure == nullptr && score(p, k, d, rec);
  record(p, k, d, x.response, wake_ns - scheduled_ns, rec);

  if (x.failure != nullptr) {
    fault(x.failure);
  } else if (k + 1 >= p.total_samples || last_trial_played) {
    end_run(RunEnd::kCompleted, "");
  } else if (stop_requested_.exchange(false, std::memory_order_acq_rel)) {
    end_run(RunEnd::kStopped, "stopped by request");
  }
}

BenchLoop::TickDrive BenchLoop::drive(RunProgram& p, std::uint64_t k, SampleRecord& rec) noexcept {
  TickDrive d;
  if (p.kind != RunKind::kTrack || k < p.excitation.size()) {
    // An open-loop drive (identify, excite), or the pre-conditioning prefix of a tracking run.
    d.u_request = p.excitation[k];
    rec.u_ff = d.u_request;
  } else {
    track_drive(p, k, d, rec);
  }
  rec.reference = d.y_ref;
  return d;
}

double BenchLoop::twin_feedforward(RunProgram& p, double t) const noexcept {
  const double none = std::numeric_limits<double>::quiet_NaN();  // its feedback holds
  auto target_at = [&p](double tt) noexcept {
    return p.feedforward_target(tt, p.learned_twin_offset_um);
  };
  if (p.twin_targets.capacity() > 1) {
    return p.learned_twin->step(none, none, p.twin_targets.advance(t, dt_, target_at)).u_ff;
  }
  return p.learned_twin->step(none, none, target_at(t)).u_ff;
}

void BenchLoop::track_drive(RunProgram& p, std::uint64_t k, TickDrive& d,
                            SampleRecord& rec) noexcept {
  const double t = static_cast<double>(k - p.excitation.size()) * dt_;
  d.y_ref = p.reference->value(t);
  if (d.y_ref < p.y_ref_min || d.y_ref > p.y_ref_max) {
    d.y_ref = std::min(std::max(d.y_ref, p.y_ref_min), p.y_ref_max);
    rec.flags |= kSampleReferenceLimited;
    ++p.counters.reference_clips;
  }
  // The feedforward's target at run time tt: the reference, or with a preview the static
  // target that inverts the model's delay and dynamics (the reference ahead by the delay).
  // Less the tare: the output offset the model did not predict on the open-loop prefix, and
  // from the first scored tick of a periodic reference the mean error of its start-up period.
  // A drive learned before: the offset taken off when it was learned, and from trial 0 on
  // also the offset its lead-in measured.
  const double tare = p.learning ? p.learning->target_offset(k, p.tare.um()) : p.tare.um_at(k);
  auto target_at = [&p, tare](double tt) noexcept { return p.feedforward_target(tt, tare); };
  // The feedback's reference; before feedback_from NaN: the PID holds (RunProgram).
  const double fb_ref = k < p.feedback_from ? std::numeric_limits<double>::quiet_NaN() : d.y_ref;
  compensation::CompensatorOutput out;
  if (p.targets.capacity() > 1) {
    out = p.compensator->step(fb_ref, y_prev_, p.targets.advance(t, dt_, target_at));
  } else {
    out = p.compensator->step(fb_ref, y_prev_, target_at(t));
  }
  const double twin = p.learned_twin ? twin_feedforward(p, t) : kNoTwin;
  rec.u_ff = out.u_ff;
  rec.u_fb = out.u_fb;
  d.u_compensator = out.u_ff;
  if (out.feedback_saturated) rec.flags |= kSampleFeedbackSaturated;
  d.u_request = out.u;
  if (p.learning && k >= p.learning->first_scored_tick()) {
    // A learning run: from trial 1 on the learned feedforward, with the feedback on it.
    if (simulated_) await_learned_drive(*p.learning, k);
    d.phase = p.learning->begin_tick(k);
    d.learning = true;
    if (double u_ff = out.u_ff; p.learning->learned(d.phase, u_ff, twin)) {
      rec.u_ff = u_ff;
      d.u_request = u_ff + out.u_fb;
    }
  } else if (double u_ff = out.u_ff; p.learning && p.learning->lead_in(k, u_ff, twin)) {
    rec.u_ff = u_ff;  // a drive learned before plays the start-up period too
    d.u_request = u_ff + out.u_fb;
    d.lead_in = true;
  }
}

OutputLimiter::Applied BenchLoop::limit(RunProgram& p, std::uint64_t k, double u_request,
                                        SampleRecord& rec) noexcept {
  const OutputLimiter::Applied lim = limiter_.apply(u_request);
  if (p.compensator) p.compensator->notify_saturation(lim.direction);
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
    p.tare.y_model_history[k % TareWindow::kHistory] = rec.y_model;
  }
  return lim;
}

BenchLoop::TickExchange BenchLoop::exchange(RunProgram& p, std::uint64_t k,
                                            const OutputLimiter::Applied& lim,
                                            SampleRecord& rec) noexcept {
  TickExchange x;
  if ((lim.clamped || lim.slew_limited) && options_.fatal_on_limit) {
    x.failure = "output limit reached (limits.fatal_on_limit)";
  } else if (driver_.write(lim.u) != drivers::DriverStatus::kOk) {
    x.failure = "driver write failed";
  } else {
    last_u_.store(lim.u, std::memory_order_relaxed);
    drivers::Measurement m;
    const auto st = driver_.read(m);
    if (st == drivers::DriverStatus::kStale) {
      rec.flags |= kSampleStale;
      ++p.counters.stale_reads;
      stuck_.stale(lim.u);
    } else if (st != drivers::DriverStatus::kOk) {
      x.failure =
          st == drivers::DriverStatus::kTimeout ? "driver read timed out" : "driver read failed";
    }
    if (x.failure == nullptr && !std::isfinite(m.position_um)) {
      x.failure = "measurement is not a finite number";
    } else if (st == drivers::DriverStatus::kOk &&
               stuck_.update(lim.u, m.position_um, m.response_ticks)) {
      x.failure = "sensor stuck: the same reading while the output moved (loop.stuck_sensor_ms)";
    }
    rec.y_measured = m.position_um;
    if (st == drivers::DriverStatus::kOk) {
      x.response = static_cast<std::uint32_t>(
          std::min<std::uint64_t>(m.response_ticks, RunRecords::kNoFreshReading - 1));
    }
    if (x.failure == nullptr) {
      // A stale reading is the last fresh one again: the feedback must not integrate an error
      // that only the reading's age makes. It holds until the next fresh one.
      y_prev_ = st == drivers::DriverStatus::kOk ? m.position_um
                                                 : std::numeric_limits<double>::quiet_NaN();
      last_y_.store(m.position_um, std::memory_order_relaxed);
      if (st == drivers::DriverStatus::kOk) add_tare_sample(p, k, m);
    }
  }
  if (x.failure == nullptr && p.counters.overruns > options_.overrun_budget) {
    x.failure = "overrun budget exceeded (loop.overrun_budget)";
  }
  if (x.failure != nullptr) rec.flags |= kSampleFault;
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
  if (k >= p.tare.startup_from && k < p.tare.startup_to && std::isfinite(d.y_ref) &&
      std::isfinite(rec.y_measured)) {
    p.tare.startup_sum += rec.y_measured - d.y_ref;
    ++p.tare.startup_samples;
  }
  if (d.lead_in) {
    p.learning->lead_in_error(k, d.y_ref - rec.y_measured, p.tare.um());
    // A lead-in that ends early moves the scored part (and the feedback's start) up with it.
    if (const std::uint64_t first = p.learning->first_scored_tick(); first < p.metrics_from) {
      if (p.feedback_from == p.metrics_from) p.feedback_from = first;
      p.metrics_from = first;
    }
  }
  if (!d.learning) return false;
  return p.learning->end_tick(d.phase, rec.u_ff, d.u_compensator, d.y_ref - rec.y_measured);
}

void BenchLoop::record(RunProgram& p, std::uint64_t k, const TickDrive& d, std::uint32_t response,
                       std::int64_t wake_latency_ns, SampleRecord& rec) noexcept {
  if (p.records.count < p.records.capacity && k >= p.metrics_from) {
    p.records.u[p.records.count] = rec.u_out;
    p.records.y[p.records.count] = rec.y_measured;
    p.records.yr[p.records.count] = d.y_ref;
    if (!p.records.response.empty()) p.records.response[p.records.count] = response;
    ++p.records.count;
  }
  rec.exec_ns = now_ns() - exec_start_ns_;
  log_sample(p, rec);
  p.stats.record(wake_latency_ns, rec.exec_ns, overran_);
  p.done.store(k + 1, std::memory_order_release);
  if (d.learning && d.phase + 1 == p.learning->period) signal_event();  // a trial for the learner
}

void BenchLoop::await_learned_drive(const LearningExchange& learning, std::uint64_t k) noexcept {
  // Virtual time waits for the learner, as for the log writer: each period after a trial plays
  // the drive learned from it. A stop, an abort or a shutdown ends the wait.
  while (learning.owed(k) && !quit_.load(std::memory_order_acquire) &&
         !stop_requested_.load(std::memory_order_acquire) &&
         !abort_requested_.load(std::memory_order_acquire)) {
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
}

void BenchLoop::end_run(RunEnd end, const char* reason) noexcept {
  RunProgram* p = active_;
  if (p == nullptr) return;
  p->end = end;
  p->end_reason = reason;
  active_ = nullptr;
  driver_.set_run_active(false);
  active_pub_.store(nullptr, std::memory_order_release);
  if (end != RunEnd::kFault) state_.store(State::kIdle, std::memory_order_release);
  finished_.store(p, std::memory_order_release);
  signal_event();
}

void BenchLoop::fault(const char* reason) noexcept {
  driver_.safe_state();
  limiter_.reset(driver_.safe_output_v());
  last_u_.store(driver_.safe_output_v(), std::memory_order_relaxed);
  fault_reason_.store(reason, std::memory_order_release);
  state_.store(State::kFault, std::memory_order_release);
  end_run(RunEnd::kFault, reason);
  signal_event();
}

}  // namespace hystbench::daemon
