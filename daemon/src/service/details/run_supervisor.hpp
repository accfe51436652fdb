#pragma once
// The bench's run supervisor: where the bench is with its run (RunPhase), the run queued for its
// preparation and what stop or abort asked for meanwhile, the active run as status and progress
// show it, and the supervisor thread. That thread prepares a queued run and hands it to the
// loop, announces each run and segment (run.progress), reports progress every 0.5 s, and hands
// each run the loop finished to the bench (Hooks::finished), which makes its result and calls
// deliver(). launch() names a built run, opens its log and starts it. It shares the bench's mutex
// (one lock guards the bench's state and its run's): each method says whether it takes the lock or
// expects it held. Not real-time safe; the loop thread never calls it.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "hystbench/daemon/config/bench_settings.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"
#include "runs/details/run_context.hpp"

namespace hystbench::daemon::details {

/// kPreparing: started, its preparation (track's planned feedforward) queued or under way on
/// the supervisor thread, not yet on the loop (stop and abort cancel it); kRunning: submitted to
/// the loop (stop and abort act on it); kFinalizing: ended, its result or identify's fit being
/// made.
enum class RunPhase { kIdle, kPreparing, kRunning, kFinalizing };

class RunSupervisor {
 public:
  using EventSink = std::function<void(const nlohmann::json&)>;
  /// What the bench does with its runs (each called on the supervisor thread, no lock held).
  struct Hooks {
    /// A run the loop played and handed back: its result, then deliver().
    std::function<void(std::unique_ptr<RunProgram>)> finished;
    /// Each wake-up, before a finished run is taken (a learning run's trials).
    std::function<void()> poll;
    /// A run that ends unplayed (stopped, aborted or refused while it was prepared, or queued
    /// as the daemon shut down), with why: its result, then deliver().
    std::function<void(std::unique_ptr<RunProgram>, RunEnd, const std::string&)> unplayed;
  };

  /// The bench's loop, its mutex and its settings (the log folder, the loop's rate); each
  /// outlives the supervisor.
  RunSupervisor(BenchLoop& loop, std::mutex& mutex, const BenchSettings& settings)
      : loop_(loop), mutex_(mutex), settings_(settings) {}
  ~RunSupervisor();
  RunSupervisor(const RunSupervisor&) = delete;
  RunSupervisor& operator=(const RunSupervisor&) = delete;

  /// Starts the supervisor thread.
  void start(Hooks hooks);
  /// Once: quitting() from now on (false when it was already). The loop's shutdown wakes the
  /// thread; join() then waits for it.
  bool quit() noexcept { return !quit_.exchange(true); }
  bool quitting() const noexcept { return quit_.load(); }
  /// After quit(): waits for the thread, then ends a run still queued for its preparation
  /// unplayed (Hooks::unplayed).
  void join();

  // ---- the caller holds the mutex ----
  RunPhase phase() const noexcept { return phase_; }
  /// Throws CommandError busy unless the bench is idle.
  void require_idle() const;
  /// The active run (run_id, kind, total, log, stage ...) as status shows it; null when idle.
  const nlohmann::json& active() const noexcept { return active_; }
  /// The active run's stage, as status and run.progress name it (nothing when idle).
  void set_stage(const std::string& stage);
  /// Names a built run `<UTC second>-<kind>-<n>` (n counts up; a name whose log is in the log
  /// folder already is skipped), opens its log, then hands it to the loop, or with a preparation
  /// queues it for the supervisor thread; it is the active run from then on. Returns the start
  /// reply: run_id, samples, duration_s, log, and the builder's reply. Throws CommandError
  /// log_error (the log does not open) or busy (the loop refuses the run; its log closed).
  nlohmann::json launch(const char* kind, BuiltRun run);
  /// A segment of the active run (identify's verification or responses, a stage's responses):
  /// submitted to the loop, the active run's stage, total and `log_key` set to it. False with
  /// `why` (its log closed) when the daemon shuts down or the loop refuses it.
  bool submit_segment(std::unique_ptr<RunProgram> segment, const std::string& stage,
                      const char* log_key, std::string& why);
  /// The run ended: its result is being made (`stage` says what, where given).
  void finalizing(const std::string& stage = "");

  // ---- these take the mutex ----
  /// stop: ends the active run normally, or cancels its preparation. CommandError no_run.
  nlohmann::json stop();
  /// abort: the run (or its preparation) ends aborted; whether one was active.
  bool abort();
  /// The run's result: `keep` records it (under the lock), the bench goes idle, run.finished
  /// goes out; wait_idle() returns once it has.
  void deliver(nlohmann::json result, const std::function<void(const nlohmann::json&)>& keep);
  /// Waits until no run is in any phase and the last run.finished has reached the sink.
  bool wait_idle(std::chrono::milliseconds timeout);
  void set_sink(EventSink sink);
  /// Sends an event to the sink (any thread; the sink is called without the lock).
  void emit(const nlohmann::json& event);

 private:
  /// A run submitted to the loop is the active one; the supervisor announces it.
  void running(nlohmann::json active);
  /// A run queued for its preparation on the supervisor thread, which then submits it.
  void queue(std::unique_ptr<RunProgram> run, std::unique_ptr<RunPreparation> preparation,
             nlohmann::json active);
  /// Hands `run` to the loop; false when the loop refuses it (its log is closed then).
  bool submit_to_loop(std::unique_ptr<RunProgram> run);
  std::string new_run_id(const char* kind);
  void supervise();
  /// run.progress once for a run or segment not announced yet.
  void announce();
  /// run.progress of the active run; `started`: also when the loop no longer (or not yet)
  /// plays it, with done = 0.
  void emit_progress(bool started = false);
  bool preparation_queued() const;
  /// Runs the queued preparation, then hands the run to the loop; a cancelled one ends unplayed.
  void prepare();

  BenchLoop& loop_;
  std::mutex& mutex_;
  const BenchSettings& settings_;
  Hooks hooks_;
  // Guarded by mutex_.
  RunPhase phase_ = RunPhase::kIdle;
  nlohmann::json active_;
  bool delivering_ = false;          // run.finished is on its way to the sink
  std::condition_variable idle_cv_;  // phase_ back to kIdle and run.finished delivered
  std::unique_ptr<RunProgram> preparing_;
  std::unique_ptr<RunPreparation> preparation_;
  RunEnd cancel_ = RunEnd::kCompleted;  // what stop or abort asked of a preparation
  EventSink sink_;
  std::uint64_t run_counter_ = 0;  // the last run id's n
  // The supervisor thread's own.
  std::string announced_;  // run_id/stage last announced
  std::thread thread_;
  std::atomic<bool> quit_{false};
};

}  // namespace hystbench::daemon::details
