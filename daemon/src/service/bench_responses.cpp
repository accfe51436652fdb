// The stage's frequency responses and the feedback designed on them: frf's run and result,
// tune, and the feedback status states (Bench members; the supervisor thread finalises the
// runs). identify's own measurement is the identify coordinator's (identify_verification.cpp).
#include <spdlog/spdlog.h>

#include <mutex>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/model_file_io.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "runs/details/feedback_design.hpp"
#include "runs/details/request_params.hpp"
#include "runs/details/response_program.hpp"
#include "runs/details/run_context.hpp"
#include "runs/details/run_result.hpp"
#include "runs/details/stage_runs.hpp"
#include "service/details/model_store.hpp"
#include "service/details/run_supervisor.hpp"
#include "service/details/stage_coordinator.hpp"

namespace hystbench::daemon {

namespace hc = compensation;
using nlohmann::json;

namespace {

// The compensator a result's design is for: inverse+pid with a model, pid without.
hc::CompensatorKind default_feedback(bool model) {
  return model ? hc::CompensatorKind::kInversePid : hc::CompensatorKind::kPid;
}

}  // namespace

json Bench::feedback_now(hc::CompensatorKind kind, json* why) {
  try {
    const details::RunContext ctx = run_context();
    json f = details::plan_feedback(ctx, kind, {}).summary;
    f["compensator"] = std::string(hc::to_string(kind));
    last_feedback_ = f;
    return f;
  } catch (const std::exception& e) {
    if (why != nullptr) *why = e.what();
    return nullptr;
  }
}

json Bench::start_frf(const details::RequestParams& request) {
  std::lock_guard lock(mutex_);
  require_idle();
  if (is_stage()) return stage_->start_frf(request);
  const details::RunContext ctx = run_context();
  const sim::FrequencyResponseExcitationOptions o = details::response_options(request, ctx);
  json reply = launch("frf", details::make_response_program(o, ctx));
  frf_options_ = o;
  return reply;
}

void Bench::responses_finished(std::unique_ptr<RunProgram> run, details::RunResult result) {
  json& report = result.report;
  std::optional<sim::FrequencyResponseExcitationOptions> options;
  {
    std::lock_guard lock(mutex_);
    options = std::move(frf_options_);
    frf_options_.reset();
  }
  if (run->end == RunEnd::kCompleted && options) {
    try {
      hc::StageResponses r = details::measure_responses(*run, *options);
      std::lock_guard lock(mutex_);
      report["frequency_response"] = details::responses_summary(r, models_->design_responses());
      report["frequency_response"]["measured"] = hc::to_json(r);
      models_->keep_frf_responses(std::move(r), report["frequency_response"]);
      json why;
      report["feedback"] = feedback_now(default_feedback(models_->active() != nullptr), &why);
      if (report["feedback"].is_null()) report["feedback_error"] = why;
    } catch (const std::exception& e) {
      report["frequency_response_error"] = e.what();
      spdlog::error("run {}: the frequency response: {}", run->run_id, e.what());
    }
  } else {
    report["frequency_response_error"] = "the run did not complete: nothing was measured";
  }
  deliver_result(std::move(report));
}

json Bench::tune(const details::RequestParams& request) {
  std::lock_guard lock(mutex_);
  const bool has_model = is_stage() ? stage_->model() != nullptr : models_->active() != nullptr;
  const std::string name = request.string("compensator", has_model ? "inverse+pid" : "pid");
  const auto kind = hc::compensator_kind_from_string(name);
  if (!kind || !hc::uses_feedback(*kind)) {
    throw common::CommandError("bad_params",
                               "compensator: '" + name + "' has no feedback (inverse+pid, pid)");
  }
  if (hc::needs_model(*kind) && !has_model) {
    throw common::CommandError("no_model", "inverse+pid needs a model: identify or load one");
  }
  details::FeedbackGainsRequest gains;
  if (request.has("kp")) gains.kp = request.number("kp", 0.0);
  if (request.has("ki")) gains.ki = request.number("ki", 0.0);
  if (request.has("kd")) gains.kd = request.number("kd", 0.0);
  gains.force = true;  // tune states a hand law's margins; it refuses nothing, as it runs nothing
  const details::RunContext ctx = run_context();
  if (is_stage()) {
    json out = details::stage_tune(ctx, stage_->model(), stage_->axis_outputs(), settings_.axes,
                                   *kind, gains);
    out["compensator"] = name;
    return out;
  }
  const details::FeedbackPlan plan = details::plan_feedback(ctx, *kind, gains);
  json out = plan.summary;
  out["compensator"] = name;
  out["curves"] = details::loop_curves(plan, dt_);
  last_feedback_ = plan.summary;
  last_feedback_["compensator"] = name;
  return out;
}

}  // namespace hystbench::daemon
