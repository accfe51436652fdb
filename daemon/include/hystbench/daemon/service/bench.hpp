#pragma once
// The bench: owns the driver, the loop, the active model and the runs; answers commands.
// Commands arrive as (cmd, params) JSON from the socket server's thread; run completion,
// progress events and model fitting happen on the bench's supervisor thread. Nothing here runs
// on the loop thread except through BenchLoop.
#include <atomic>
#include <condition_variable>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hystbench/common/command_error.hpp"
#include "hystbench/compensation/compensator.hpp"
#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/stage_responses.hpp"
#include "hystbench/daemon/config/bench_settings.hpp"
#include "hystbench/daemon/config/config.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/daemon/runs/upload_store.hpp"
#include "hystbench/drivers/driver.hpp"
#include "hystbench/sim/identification_excitation.hpp"

namespace hystbench::daemon {

namespace details {
class RequestParams;
struct Command;
struct RunContext;
struct PlanCache;
struct FeedbackPlanCache;
struct IdentifyRequest;
class RunHistory;
class ModelStore;
class ModelStateTracker;
class RunSupervisor;
class IdentifyCoordinator;
class LearningRuns;
class StageCoordinator;
class FeedbackDesigner;
class RunHandback;
std::span<const Command> bench_commands();
}  // namespace details

class Bench {
 public:
  using EventSink = std::function<void(const nlohmann::json&)>;

  /// Creates, configures and activates the driver. Throws std::runtime_error naming the cause.
  explicit Bench(BenchSettings settings);
  ~Bench();
  Bench(const Bench&) = delete;
  Bench& operator=(const Bench&) = delete;

  /// Starts the loop and the supervisor; returns the real-time setup report.
  RealtimeReport start();
  /// Ends a run (aborted, log closed), safe output, stops threads, deactivates the driver.
  void shutdown();

  /// Executes one command of connection `client` (its uploads are its own); returns its result
  /// object. Throws CommandError. Any thread: commands run one at a time, in arrival order.
  nlohmann::json handle(const std::string& cmd, const nlohmann::json& params,
                        std::uint64_t client = 0);
  /// Connection `client` went away: its uploads are discarded (a run already started keeps
  /// what it took).
  void client_closed(std::uint64_t client);
  /// Receives progress and run events (from the supervisor thread).
  void set_event_sink(EventSink sink);
  /// What status shows under "http": the live view's address and whether it controls runs
  /// (null, the default: no view).
  void set_web_view_status(nlohmann::json view);

  /// True when the loop has ticked since the previous call (for the systemd watchdog).
  bool loop_advanced();
  /// Waits until no run is active or pending finalisation and the last run's `run.finished`
  /// event has reached the sink (for tests and shutdown).
  bool wait_idle(std::chrono::milliseconds timeout);
  BenchLoop& loop() { return *loop_; }
  drivers::Driver& driver() { return *driver_; }

 private:
  // The socket commands (command_table.cpp): its rows call these handlers with the request
  // already checked against the row's parameters.
  friend std::span<const details::Command> details::bench_commands();
  nlohmann::json status() const;
  nlohmann::json start_identify(const details::RequestParams& request);
  nlohmann::json start_track(const details::RequestParams& request, std::uint64_t client);
  /// excite: a complete drive upload played open loop after a ramp from the present output.
  nlohmann::json start_excite(const details::RequestParams& request, std::uint64_t client);
  // The frequency responses and the feedback designed on them (bench_feedback_commands.cpp; the
  // stage coordinator's or the feedback designer's).
  /// frf: the multisines that measure them, open loop; its result kept by the bench and the
  /// active model (its file saved again).
  nlohmann::json start_frf(const details::RequestParams& request);
  /// tune: the feedback a track run would get (designed, or given gains checked), with its
  /// loop's curves; runs nothing.
  nlohmann::json tune(const details::RequestParams& request);
  /// A stage of several axes (details/stage_coordinator.hpp): settings_.axes is not empty.
  bool is_stage() const noexcept { return !settings_.axes.empty(); }
  /// The active models' files: the one active model's, or on a stage each axis's RUN-AXIS.json.
  /// Caller holds mutex_.
  std::vector<std::string> active_model_paths() const;
  nlohmann::json stop_run();
  nlohmann::json abort_run();
  /// reset: leaves FAULT (reset_failed when the loop does not).
  nlohmann::json reset();
  nlohmann::json model_get() const;
  /// model.load: {"model": document, "name": file name} (kept in the model folder) or
  /// {"stored": name in the model folder}; never a path.
  nlohmann::json load_model(const details::RequestParams& request);
  /// model.list: the model folder's *.json files (name, bytes, type, active).
  nlohmann::json list_models() const;
  /// model.delete: a model or learned drive out of the model folder (not the active model).
  nlohmann::json delete_model(const details::RequestParams& request);
  /// Throws CommandError fault or busy unless a run may start. Caller holds mutex_.
  void require_idle() const;
  /// What the run builders need to know (settings, model, present output). Caller holds mutex_.
  details::RunContext run_context() const;
  /// Keeps the result as the last one and in the history; the supervisor leaves the bench idle
  /// and emits run.finished.
  void deliver_result(nlohmann::json result);
  void emit(const nlohmann::json& event);
  bool quitting() const noexcept;

  BenchSettings settings_;
  std::unique_ptr<drivers::Driver> driver_;
  std::unique_ptr<BenchLoop> loop_;
  RealtimeReport realtime_;
  double dt_;

  std::mutex commands_mutex_;  // one command at a time, whichever thread sends it
  std::unique_ptr<details::RunHistory> history_;  // the runs, kept in log_dir (its own lock)
  mutable std::mutex mutex_;                      // guards everything below
  // The run's phase, its preparation, the active run, events and the supervisor thread
  // (details/run_supervisor.hpp; under mutex_ too).
  std::unique_ptr<details::RunSupervisor> runs_;
  // identify after its excitation: the fit, the verification, the extension (supervisor thread).
  std::unique_ptr<details::IdentifyCoordinator> identify_;
  nlohmann::json web_view_;                      // status "http"
  std::unique_ptr<details::ModelStore> models_;  // the active model and responses, the folder
  std::shared_ptr<details::PlanCache> plans_;    // track's last plan (its own lock)
  // The active model in the state the loop's output history leaves it (one axis).
  std::unique_ptr<details::ModelStateTracker> model_states_;
  std::shared_ptr<details::FeedbackPlanCache> feedback_plans_;
  // frf's runs on one axis and the feedback designed on what they measure.
  std::unique_ptr<details::FeedbackDesigner> feedback_;
  nlohmann::json last_result_;
  // A stage's model and its runs (a stage of several axes only).
  std::unique_ptr<details::StageCoordinator> stage_;
  // The learning runs' learners, their trials and kept drives (supervisor thread).
  std::unique_ptr<details::LearningRuns> learning_;
  // Each run handed back to its owner, or its result delivered (supervisor thread).
  std::unique_ptr<details::RunHandback> handback_;
  UploadStore uploads_;  // its own lock
  std::uint64_t watchdog_ticks_ = 0;
};

}  // namespace hystbench::daemon
