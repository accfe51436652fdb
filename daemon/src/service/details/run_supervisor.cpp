#include "service/details/run_supervisor.hpp"

#include <ctime>
#include <filesystem>
#include <system_error>

#include "hystbench/common/command_error.hpp"
#include "service/details/run_log.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

namespace {

constexpr const char* kRefused = "the loop did not accept the run";

}  // namespace

RunSupervisor::~RunSupervisor() {
  quit();
  if (thread_.joinable()) thread_.join();
}

void RunSupervisor::start(Hooks hooks) {
  hooks_ = std::move(hooks);
  thread_ = std::thread([this] { supervise(); });
}

void RunSupervisor::join() {
  if (thread_.joinable()) thread_.join();
  std::unique_ptr<RunProgram> run;
  {
    std::lock_guard lock(mutex_);
    run = std::move(preparing_);
    preparation_.reset();
  }
  // Queued as the bench shut down: never prepared.
  if (run)
    hooks_.unplayed(std::move(run), RunEnd::kAborted,
                    "the daemon shut down before the run started");
}

void RunSupervisor::require_idle() const {
  if (phase_ != RunPhase::kIdle) throw common::CommandError("busy", "a run is active");
}

void RunSupervisor::set_stage(const std::string& stage) {
  if (!active_.is_null()) active_["stage"] = stage;
}

bool RunSupervisor::submit_to_loop(std::unique_ptr<RunProgram> run) {
  std::unique_ptr<RunProgram> refused = loop_.submit(std::move(run));
  if (refused) refused->log->close();
  return refused == nullptr;
}

std::string RunSupervisor::new_run_id(const char* kind) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
  // A daemon restarted within the second counts from 1 again: an id whose log is there
  // already is taken by the run before the restart.
  std::string id;
  std::error_code ec;
  do {
    id = std::string(stamp) + "-" + kind + "-" + std::to_string(++run_counter_);
  } while (std::filesystem::exists(std::filesystem::path(settings_.log_dir) / (id + ".csv"), ec));
  return id;
}

json RunSupervisor::launch(const char* kind, BuiltRun run) {
  RunProgram& program = *run.program;
  program.run_id = new_run_id(kind);
  // The request's runs (identify's segments) follow each other after a fixed gap on the
  // simulated clock, however long the bench computes between them; released with its result.
  loop_.hold_time_between_runs(true);
  struct ReleaseUnlessLaunched {  // a log that cannot open launches nothing: paced idle again
    BenchLoop& loop;
    bool launched = false;
    ~ReleaseUnlessLaunched() {
      if (!launched) loop.hold_time_between_runs(false);
    }
  } hold{loop_};
  open_run_log(program, run.header, settings_);
  const std::string run_id = program.run_id, log_path = program.log->path().string();
  const std::uint64_t total = program.total_samples;
  json active = {{"run_id", run_id}, {"kind", kind}, {"total", total}, {"log", log_path}};
  active.update(run.status);
  if (run.preparation.work) {
    // Prepared on the supervisor thread, then submitted: the reply does not wait for it.
    queue(std::move(run.program), std::make_unique<RunPreparation>(std::move(run.preparation)),
          std::move(active));
  } else {
    if (!submit_to_loop(std::move(run.program))) throw common::CommandError("busy", kRefused);
    running(std::move(active));
  }
  json reply = {{"run_id", run_id},
                {"samples", total},
                {"duration_s", static_cast<double>(total) / settings_.loop.rate_hz},
                {"log", log_path}};
  reply.update(run.reply);
  hold.launched = true;
  return reply;
}

void RunSupervisor::running(json active) {
  active_ = std::move(active);
  phase_ = RunPhase::kRunning;
  loop_.wake_control();  // the supervisor announces the run
}

void RunSupervisor::queue(std::unique_ptr<RunProgram> run,
                          std::unique_ptr<RunPreparation> preparation, json active) {
  active_ = std::move(active);
  active_["stage"] = preparation->stage;
  preparing_ = std::move(run);
  preparation_ = std::move(preparation);
  cancel_ = RunEnd::kCompleted;
  phase_ = RunPhase::kPreparing;
  loop_.wake_control();
}

bool RunSupervisor::submit_segment(std::unique_ptr<RunProgram> segment, const std::string& stage,
                                   const char* log_key, std::string& why) {
  if (quit_.load()) {
    segment->log->close();
    why = "daemon shutting down";
    return false;
  }
  const std::uint64_t total = segment->total_samples;
  const std::string log = segment->log->path().string();
  if (!submit_to_loop(std::move(segment))) {
    why = kRefused;
    return false;
  }
  active_["stage"] = stage;
  active_["total"] = total;
  active_[log_key] = log;
  phase_ = RunPhase::kRunning;  // stop and abort now act on the segment
  return true;
}

void RunSupervisor::finalizing(const std::string& stage) {
  phase_ = RunPhase::kFinalizing;
  if (!stage.empty()) set_stage(stage);
}

json RunSupervisor::stop() {
  {
    std::lock_guard lock(mutex_);
    if (phase_ == RunPhase::kPreparing) {  // ends unplayed once the preparation stops
      if (cancel_ == RunEnd::kCompleted) cancel_ = RunEnd::kStopped;
      return {{"stopping", true}};
    }
    // A run submitted but not yet picked up by the loop counts as active.
    if (phase_ != RunPhase::kRunning) throw common::CommandError("no_run", "no run is active");
  }
  loop_.request_stop();
  return {{"stopping", true}};
}

bool RunSupervisor::abort() {
  bool active = false;
  {
    std::lock_guard lock(mutex_);
    active = phase_ == RunPhase::kRunning || phase_ == RunPhase::kPreparing;
    if (phase_ == RunPhase::kPreparing) cancel_ = RunEnd::kAborted;
  }
  loop_.request_abort();
  return active;
}

void RunSupervisor::deliver(json result, const std::function<void(const json&)>& keep) {
  {
    std::lock_guard lock(mutex_);
    keep(result);
    active_ = nullptr;
    phase_ = RunPhase::kIdle;
    delivering_ = true;
  }
  loop_.hold_time_between_runs(false);
  // Clients may start the next run as soon as they see this event, so the bench is idle before
  // it goes out; wait_idle() still waits for it, or a caller could read the previous result.
  emit({{"event", "run.finished"}, {"result", result}});
  {
    std::lock_guard lock(mutex_);
    delivering_ = false;
  }
  idle_cv_.notify_all();
}

bool RunSupervisor::wait_idle(std::chrono::milliseconds timeout) {
  // The loop runs only what the bench submits: with no run in any phase it is not running.
  std::unique_lock lock(mutex_);
  return idle_cv_.wait_for(lock, timeout,
                           [this] { return phase_ == RunPhase::kIdle && !delivering_; });
}

void RunSupervisor::set_sink(EventSink sink) {
  std::lock_guard lock(mutex_);
  sink_ = std::move(sink);
}

void RunSupervisor::emit(const json& event) {
  EventSink sink;
  {
    std::lock_guard lock(mutex_);
    sink = sink_;
  }
  if (sink) sink(event);
}

void RunSupervisor::supervise() {
  constexpr auto kProgressPeriod = std::chrono::milliseconds(500);
  auto next_progress = std::chrono::steady_clock::now() + kProgressPeriod;
  while (!quit_.load()) {
    // Read before looking, so a run that ends in between wakes the wait at once.
    const std::uint32_t seen = loop_.events();
    if (preparation_queued()) {
      prepare();
      continue;
    }
    // Before a finished run is taken: on the simulated clock a run can end before the first
    // periodic event, and a client still sees it (and each verification stage) start.
    announce();
    hooks_.poll();
    if (auto finished = loop_.take_finished()) {
      hooks_.finished(std::move(finished));
      continue;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= next_progress) {
      next_progress = now + kProgressPeriod;
      emit_progress();
    }
    loop_.wait_event(seen, next_progress - now);
  }
}

void RunSupervisor::announce() {
  std::string key;
  {
    std::lock_guard lock(mutex_);
    if (active_.is_null() || phase_ != RunPhase::kRunning) return;
    key = active_["run_id"].get<std::string>() + "/" + active_.value("stage", "");
  }
  if (key == announced_) return;
  announced_ = key;
  emit_progress(true);
}

void RunSupervisor::emit_progress(bool started) {
  json run;
  {
    std::lock_guard lock(mutex_);
    run = active_;
  }
  const RunProgram* p = loop_.active();
  if (run.is_null() || (p == nullptr && !started)) return;
  // A run that already ended (or is not picked up yet) is announced at its start.
  const std::uint64_t done = p != nullptr ? p->done.load(std::memory_order_acquire) : 0;
  const auto total = run["total"].get<std::uint64_t>();
  json event = {
      {"event", "run.progress"}, {"run_id", run["run_id"]},
      {"kind", run["kind"]},     {"done", done},
      {"total", total},          {"fraction", total ? static_cast<double>(done) / total : 0.0}};
  if (run.contains("stage")) event["stage"] = run["stage"];  // identify's verification
  emit(event);
}

bool RunSupervisor::preparation_queued() const {
  std::lock_guard lock(mutex_);
  return preparing_ != nullptr;
}

void RunSupervisor::prepare() {
  std::unique_ptr<RunProgram> run;
  std::unique_ptr<RunPreparation> preparation;
  {
    std::lock_guard lock(mutex_);
    run = std::move(preparing_);
    preparation = std::move(preparation_);
  }
  const json progress = {{"event", "run.progress"},      {"run_id", run->run_id},
                         {"kind", to_string(run->kind)}, {"done", 0},
                         {"total", run->total_samples},  {"stage", preparation->stage}};
  bool cancelled = false;
  try {
    preparation->work(*run, [&](double fraction) {
      {
        std::lock_guard lock(mutex_);
        if (cancel_ != RunEnd::kCompleted || quit_.load()) throw PreparationCancelled{};
      }
      json event = progress;
      event["fraction"] = fraction;
      emit(event);
    });
  } catch (const PreparationCancelled&) {
    cancelled = true;
  }
  RunEnd cancel = RunEnd::kCompleted;
  {
    std::lock_guard lock(mutex_);
    cancel = cancel_;
    if (quit_.load()) cancel = RunEnd::kAborted;
    if (!cancelled && cancel == RunEnd::kCompleted) {
      active_.erase("stage");
      if (auto refused = loop_.submit(std::move(run))) {
        run = std::move(refused);
      } else {
        phase_ = RunPhase::kRunning;
        return;
      }
    }
  }
  if (cancel == RunEnd::kCompleted) {
    hooks_.unplayed(std::move(run), RunEnd::kAborted,
                    loop_.state() == BenchLoop::State::kFault
                        ? std::string("the loop went into FAULT (") + loop_.fault_reason() +
                              ") while the run was prepared: nothing was played"
                        : "the loop did not accept the run: nothing was played");
    return;
  }
  hooks_.unplayed(std::move(run), cancel,
                  std::string(cancel == RunEnd::kStopped ? "stopped" : "aborted") + " while " +
                      preparation->stage + ": nothing was played");
}

}  // namespace hystbench::daemon::details
