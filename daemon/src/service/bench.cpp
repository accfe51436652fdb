#include "hystbench/daemon/service/bench.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "hystbench/compensation/number_text.hpp"
#include "runs/details/excite_program.hpp"
#include "runs/details/feedback_design.hpp"
#include "runs/details/identify_program.hpp"
#include "runs/details/learned_drive.hpp"
#include "runs/details/run_context.hpp"
#include "runs/details/run_result.hpp"
#include "runs/details/stage_runs.hpp"
#include "runs/details/track_program.hpp"
#include "service/details/command_table.hpp"
#include "service/details/feedback_designer.hpp"
#include "service/details/identify_coordinator.hpp"
#include "service/details/learning_runs.hpp"
#include "service/details/model_folder.hpp"
#include "service/details/model_state_tracker.hpp"
#include "service/details/model_store.hpp"
#include "service/details/run_handback.hpp"
#include "service/details/run_history.hpp"
#include "service/details/run_supervisor.hpp"
#include "service/details/stage_coordinator.hpp"

namespace hystbench::daemon {

namespace hc = compensation;
using nlohmann::json;

namespace {

const char* state_name(BenchLoop::State s) {
  switch (s) {
    case BenchLoop::State::kStopped:
      return "stopped";
    case BenchLoop::State::kIdle:
      return "idle";
    case BenchLoop::State::kRunning:
      return "running";
    case BenchLoop::State::kFault:
      return "fault";
  }
  return "unknown";
}

}  // namespace

Bench::Bench(BenchSettings settings)
    : settings_(std::move(settings)),
      history_(std::make_unique<details::RunHistory>(settings_.log_dir)),
      models_(std::make_unique<details::ModelStore>(
          settings_.model_dir, settings_.loop.limits.u_min, settings_.loop.limits.u_max)),
      plans_(std::make_shared<details::PlanCache>()),
      feedback_plans_(std::make_shared<details::FeedbackPlanCache>()) {
  dt_ = 1.0 / settings_.loop.rate_hz;
  try {
    driver_ = drivers::make_driver(settings_.driver_type);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  if (auto r = driver_->configure(settings_.driver_params, settings_.loop.rate_hz); !r) {
    throw std::runtime_error(r.message);
  }
  auto& lim = settings_.loop.limits;
  if (lim.u_min < driver_->output_min_v() || lim.u_max > driver_->output_max_v()) {
    throw std::runtime_error("limits.u_min/u_max [" + std::to_string(lim.u_min) + ", " +
                             std::to_string(lim.u_max) + "] V exceed the driver's output range [" +
                             std::to_string(driver_->output_min_v()) + ", " +
                             std::to_string(driver_->output_max_v()) + "] V");
  }
  if (auto r = driver_->serves(std::max<std::size_t>(1, settings_.axes.size())); !r) {
    throw std::runtime_error(r.message);
  }
  if (settings_.axes.empty() && driver_->axes() > 1) {
    throw std::runtime_error("the driver serves " + std::to_string(driver_->axes()) +
                             " axes and the configuration names none");
  }
  if (auto r = driver_->activate(); !r) throw std::runtime_error(r.message);
  BenchLoopOptions loop = settings_.loop;
  loop.axis_names = settings_.axes;
  loop_ = std::make_unique<BenchLoop>(*driver_, loop);
  model_states_ = std::make_unique<details::ModelStateTracker>(loop_->output_history(), dt_);
  runs_ = std::make_unique<details::RunSupervisor>(*loop_, mutex_, settings_);
  // What every component asks of the bench: the run builders' context, a result delivered.
  details::RunHooks hooks;
  hooks.run_context = [this] { return run_context(); };
  hooks.deliver = [this](json result) { deliver_result(std::move(result)); };
  details::IdentifyCoordinator::Hooks identify;
  identify.run_context = hooks.run_context;
  identify.adopt = [this](hc::ModelFile file, const std::string& path,
                          const std::optional<hc::StageResponses>& responses, json* why) {
    if (responses) models_->set_measured_responses(*responses);
    models_->adopt(std::move(file), path);
    return feedback_->feedback_now(hc::CompensatorKind::kInversePid, why);
  };
  identify.deliver = hooks.deliver;
  const details::BenchParts parts{settings_, *loop_, *runs_, mutex_};
  identify_ = std::make_unique<details::IdentifyCoordinator>(parts, std::move(identify));
  learning_ = std::make_unique<details::LearningRuns>(
      parts, [this](const std::string& axis) -> std::string {
        if (!axis.empty()) return stage_ ? stage_->model_file(axis) : "";
        const std::string path = models_->active_path();
        return path.empty() ? path : std::filesystem::path(path).filename().string();
      });
  feedback_ = std::make_unique<details::FeedbackDesigner>(parts, *models_, hooks);
  if (is_stage()) {
    stage_ =
        std::make_unique<details::StageCoordinator>(parts, *models_, *learning_, uploads_, hooks);
  }
  handback_ = std::make_unique<details::RunHandback>(
      parts, details::RunHandback::Owners{*identify_, *learning_, *feedback_, stage_.get(),
                                          hooks.deliver});
}

Bench::~Bench() {
  // A run that cannot be written out at exit (full disk) is logged, not rethrown from here.
  try {
    shutdown();
  } catch (const std::exception& e) {
    spdlog::error("bench shutdown: {}", e.what());
  }
}

RealtimeReport Bench::start() {
  realtime_ = loop_->start();
  runs_->start({[this](std::unique_ptr<RunProgram> run) { handback_->played(std::move(run)); },
                [this] { learning_->poll(); },
                [this](std::unique_ptr<RunProgram> run, RunEnd end, const std::string& why) {
                  handback_->unplayed(std::move(run), end, why);
                }});
  return realtime_;
}

void Bench::shutdown() {
  if (!runs_->quit()) return;  // shut down already
  if (loop_) {
    loop_->request_abort();
    // Give the loop a few ticks (at most 0.2 s) to end the run cleanly, then stop it.
    loop_->wait_for([this] { return loop_->state() != BenchLoop::State::kRunning; },
                    std::chrono::milliseconds(200));
    loop_->shutdown();
  }
  runs_->join();
  if (loop_) {
    if (auto finished = loop_->take_finished()) handback_->played(std::move(finished));
  }
  if (driver_) {
    driver_->safe_state();
    driver_->deactivate();
  }
}

void Bench::set_event_sink(EventSink sink) { runs_->set_sink(std::move(sink)); }

void Bench::set_web_view_status(nlohmann::json view) {
  std::lock_guard lock(mutex_);
  web_view_ = std::move(view);
}

void Bench::emit(const json& event) { runs_->emit(event); }

bool Bench::quitting() const noexcept { return runs_->quitting(); }

bool Bench::loop_advanced() {
  const std::uint64_t t = loop_->ticks();
  const bool advanced = t != watchdog_ticks_;
  watchdog_ticks_ = t;
  return advanced;
}

bool Bench::wait_idle(std::chrono::milliseconds timeout) { return runs_->wait_idle(timeout); }

json Bench::handle(const std::string& cmd, const json& params, std::uint64_t client) {
  const std::lock_guard one_at_a_time(commands_mutex_);
  const details::Command& command = details::find_command(cmd, params);
  const details::RequestParams request(params, command.params);
  return command.handle(*this, request, client);
}

json Bench::stop_run() { return runs_->stop(); }

json Bench::abort_run() {
  const bool active = runs_->abort();
  return {{"aborted", active}, {"output_v", driver_->safe_output_v()}};
}

json Bench::reset() {
  const bool was_fault = loop_->state() == BenchLoop::State::kFault;
  if (was_fault && !loop_->reset_fault()) {
    throw common::CommandError("reset_failed", "the loop did not leave FAULT");
  }
  return {{"was_fault", was_fault}, {"state", state_name(loop_->state())}};
}

json Bench::model_get() const {
  std::lock_guard lock(mutex_);
  if (is_stage()) {
    if (stage_->model() == nullptr)
      throw common::CommandError("no_model", "no stage model (identify the stage first)");
    return stage_->status();
  }
  return models_->get();
}

void Bench::client_closed(std::uint64_t client) { uploads_.drop_client(client); }

json Bench::status() const {
  json s;
  const auto state = loop_->state();
  std::lock_guard lock(mutex_);
  const details::RunPhase phase = runs_->phase();
  const bool finalizing =
      phase == details::RunPhase::kFinalizing && state == BenchLoop::State::kIdle;
  const bool preparing = phase == details::RunPhase::kPreparing && state == BenchLoop::State::kIdle;
  s["state"] = finalizing ? "finalizing" : preparing ? "preparing" : state_name(state);
  if (state == BenchLoop::State::kFault) s["fault_reason"] = loop_->fault_reason();
  s["output_v"] = loop_->last_output();
  s["position_um"] = loop_->last_measurement();
  if (is_stage()) {
    json axes = json::object();
    for (std::size_t a = 0; a < settings_.axes.size(); ++a) {
      axes[settings_.axes[a]] = {{"output_v", loop_->last_output(a)},
                                 {"position_um", loop_->last_measurement(a)}};
    }
    s["axes"] = axes;
    s["stage_model"] = stage_->status();
  }
  s["run"] = runs_->active();
  s["model"] = models_->summary();
  s["loop"] = {{"rate_hz", settings_.loop.rate_hz},
               {"clock", to_string(settings_.loop.clock)},
               {"realtime", realtime_.summary(settings_.loop.realtime)},
               {"degraded", realtime_.degraded()},
               {"statistics", to_json(loop_->statistics())}};
  s["driver"] = driver_->diagnostics();
  s["uploads"] = {{"open", uploads_.open()},
                  {"staged_samples", uploads_.staged_samples()},
                  {"max_samples", uploads_.limits().max_samples}};
  s["feedback"] = feedback_->last();
  s["last_result"] = last_result_;
  s["faults"] = history_->faults();
  s["http"] = web_view_;
  return s;
}

nlohmann::json Bench::load_model(const details::RequestParams& request) {
  const bool stored = request.has("stored");
  const bool document = request.has("model");
  const bool documents = request.has("models");
  if (static_cast<int>(stored) + static_cast<int>(document) + static_cast<int>(documents) != 1) {
    throw common::CommandError("bad_params",
                               "give one of 'model' (the model document), 'models' (a stage's, by "
                               "axis) or 'stored' (a name from model.list)");
  }
  if (documents && !is_stage()) {
    throw common::CommandError("not_on_stage",
                               "models: a stage's key (several axes); this bench drives one axis "
                               "(model)");
  }
  // Checked first: a refused request changes nothing (an upload is not kept either).
  std::lock_guard lock(mutex_);
  if (runs_->phase() != details::RunPhase::kIdle) {
    throw common::CommandError("busy", "a run is active; load the model after it");
  }
  if (is_stage()) return stage_->load_model(request);
  if (stored) return models_->load_stored(request.string("stored", ""));
  return models_->load_document(request.string("name"), request.params()["model"]);
}

std::vector<std::string> Bench::active_model_paths() const {
  return is_stage() ? stage_->model_paths() : std::vector<std::string>{models_->active_path()};
}

nlohmann::json Bench::list_models() const {
  std::lock_guard lock(mutex_);
  return models_->list(active_model_paths());
}

nlohmann::json Bench::delete_model(const details::RequestParams& request) {
  std::lock_guard lock(mutex_);
  return models_->remove(request.string("name", ""), active_model_paths());
}

void Bench::require_idle() const {
  if (loop_->state() == BenchLoop::State::kFault) {
    throw common::CommandError("fault", std::string("the bench is in FAULT (") +
                                            loop_->fault_reason() + "); send reset first");
  }
  runs_->require_idle();
}

details::RunContext Bench::run_context() const {
  details::RunContext ctx{settings_,
                          models_->active(),
                          loop_->last_output(),
                          models_->generation(),
                          plans_,
                          models_->measured_responses(),
                          feedback_plans_};
  // A stage's axes have models of their own: each of its runs starts relaxed.
  if (ctx.model != nullptr && !is_stage()) {
    const details::ModelStateTracker::State state =
        model_states_->state(ctx.model->model, ctx.model_generation);
    ctx.model_state = state.model;
    ctx.model_history_s = state.history_s;
  }
  return ctx;
}

json Bench::start_identify(const details::RequestParams& request) {
  const details::IdentifyRequest identify = details::parse_identify_request(request, settings_);
  std::lock_guard lock(mutex_);
  require_idle();
  if (is_stage()) return stage_->start_identify(identify);
  details::BuiltRun run = details::make_identify_program(identify, run_context());
  json fit = std::move(run.fit);
  json reply = runs_->launch("identify", std::move(run));
  handback_->expect_fit(std::move(fit));
  return reply;
}

json Bench::start_excite(const details::RequestParams& request, std::uint64_t client) {
  std::lock_guard lock(mutex_);
  if (is_stage()) {
    require_idle();
    return stage_->start_excite(request, client);
  }
  if (request.has("drive_uploads")) {
    throw common::CommandError("not_on_stage",
                               "drive_uploads: a stage's key (several axes); this bench drives "
                               "one axis (drive_upload)");
  }
  if (!request.has("drive_upload")) {
    throw common::CommandError("bad_params",
                               "drive_upload: missing (the name of a complete drive upload)");
  }
  const std::string upload_name = request.string("drive_upload", "");
  require_idle();
  const auto upload = uploads_.complete(upload_name, client, UploadKind::kDrive);
  json reply = runs_->launch("excite", details::make_excite_program(*upload, run_context()));
  uploads_.erase(upload_name, client);  // the run has it now
  return reply;
}

json Bench::start_track(const details::RequestParams& request, std::uint64_t client) {
  std::lock_guard lock(mutex_);
  require_idle();
  if (is_stage()) return stage_->start_track(request, client);
  for (const char* key : {"frequencies_hz", "decouple", "decoupling", "reference_uploads"}) {
    if (request.has(key)) {
      throw common::CommandError("not_on_stage", std::string(key) +
                                                     ": a stage's key (several axes); this bench "
                                                     "drives one axis");
    }
  }
  const details::RunContext ctx = run_context();
  const details::TrackRequest track = details::parse_track_request(request, ctx);
  const std::string& upload_name = track.reference_upload;
  std::shared_ptr<const Upload> upload;
  if (!upload_name.empty()) {
    upload = uploads_.complete(upload_name, client, UploadKind::kReference);
  }
  details::BuiltRun run = details::make_track_program(track, ctx, upload.get());
  std::unique_ptr<details::TrackLearning> learning = std::move(run.learning);
  if (run.reply.contains("feedback") && run.reply["feedback"].is_object()) {
    feedback_->track_started(run.reply["feedback"], track.compensator);
  }
  json reply = runs_->launch("track", std::move(run));
  if (upload) uploads_.erase(upload_name, client);  // the run has it now
  learning_->started(reply["run_id"].get<std::string>(), std::move(learning));
  return reply;
}

void Bench::deliver_result(json result) {
  runs_->deliver(std::move(result), [this](const json& r) {
    last_result_ = r;
    history_->add(r);
  });
}

}  // namespace hystbench::daemon
