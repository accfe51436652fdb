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
          1, static_cast<std::uint64_t>(std::llround(options.held_gap_s * options.rate_hz)))) {
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
    // The targets ahead, for an inverse that uses them. Not yet with a dynamics preview, whose
    // target is already computed from the reference ahead: fed both, the rate inverse tracked
    // worse.
    if (p.compensator && !p.preview) p.targets.allocate(p.compensator->preview_samples());
    if (p.learned_twin && !p.preview) {
      p.twin_targets.allocate(p.learned_twin->preview_samples());
    }
    p.dt_s = dt_;
    // The feedback's integral holds while the drive sits at a bound of the output range.
    if (p.compensator) p.compensator->set_drive_range(options_.limits.u_min, options_.limits.u_max);
    if (p.learned_twin) {
      p.learned_twin->set_drive_range(options_.limits.u_min, options_.limits.u_max);
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
      for (std::size_t a = 0; a < axes_; ++a) {
        stuck_[a].reset(options_.stuck_sensor.latency_ticks + p->response_delay_ticks);
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
  for (std::size_t a = 0; a < axes_; ++a) last_u_[a].store(u[a], std::memory_order_relaxed);
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
  double u_compensator = 0.0;  ///< the compensator's feedforward, for a learning run
  std::size_t phase = 0;       ///< the learning trial's phase
  bool learning = false;       ///< the tick belongs to a learning run's trials, at this phase
  bool lead_in = false;        ///< a drive learned before plays the period before trial 0
};

/// What the exchange with the driver leaves for the stages after it.
struct BenchLoop::TickExchange {
  const char* failure = nullptr;  ///< why the run faults at this tick; null when it does not
  /// Per axis, the fresh reading's response_ticks.
  std::array<std::uint32_t, drivers::kMaxAxes> response{};
  TickExchange() { response.fill(RunRecords::kNoFreshReading); }
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
    record(p.axis(a), k, d[a], x.response[a], wake_ns - scheduled_ns, rec[a]);
  }
  log_sample(p, std::span<const SampleRecord>(rec).first(n));

  if (x.failure != nullptr) {
    fault(x.failure);
  } else if (k + 1 >= p.total_samples || last_trial_played) {
    end_run(RunEnd::kCompleted, "");
  } else if (stop_requested_.exchange(false, std::memory_order_acq_rel)) {
    end_run(RunEnd::kStopped, "stopped by request");
  }
}

BenchLoop::TickDrive BenchLoop::drive(std::size_t a, RunProgram& p, std::uint64_t k,
                                      SampleRecord& rec) noexcept {
  TickDrive d;
  if (p.kind != RunKind::kTrack || k < p.excitation.size()) {
    // An open-loop drive (identify, excite), or the pre-conditioning prefix of a tracking run.
    d.u_request = p.excitation[k];
    rec.u_ff = d.u_request;
  } else {
    track_drive(a, p, k, d, rec);
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

void BenchLoop::track_drive(std::size_t a, RunProgram& p, std::uint64_t k, TickDrive& d,
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
    out = p.compensator->step(fb_ref, y_prev_[a], p.targets.advance(t, dt_, target_at));
  } else {
    out = p.compensator->step(fb_ref, y_prev_[a], target_at(t));
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

OutputLimiter::Applied BenchLoop::limit(std::size_t a, RunProgram& p, std::uint64_t k,
                                        double u_request, SampleRecord& rec) noexcept {
  const OutputLimiter::Applied lim = limiters_[a].apply(u_request);
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
    p.axis(a).tare.y_model_history[k % TareWindow::kHistory] = stage[a];
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
    for (std::size_t a = 0; a < axes_; ++a) last_u_[a].store(u[a], std::memory_order_relaxed);
    std::array<drivers::Measurement, drivers::kMaxAxes> m{};
    const auto st = read_all(m);
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
      }
    }
    if (x.failure == nullptr) {
      for (std::size_t a = 0; a < axes_; ++a) {
        // A stale reading is the last fresh one again: the feedback must not integrate an error
        // that only the reading's age makes. It holds until the next fresh one.
        y_prev_[a] = st == drivers::DriverStatus::kOk ? m[a].position_um
                                                      : std::numeric_limits<double>::quiet_NaN();
        last_y_[a].store(m[a].position_um, std::memory_order_relaxed);
        if (a < n && st == drivers::DriverStatus::kOk) add_tare_sample(p.axis(a), k, m[a]);
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
