#include "service/details/feedback_designer.hpp"

#include <spdlog/spdlog.h>

#include <mutex>
#include <utility>

#include "hystbench/common/model_file_io.hpp"
#include "hystbench/daemon/loop/run_program.hpp"
#include "runs/details/feedback_design.hpp"
#include "runs/details/request_params.hpp"
#include "runs/details/response_program.hpp"
#include "runs/details/run_context.hpp"
#include "service/details/model_store.hpp"
#include "service/details/run_supervisor.hpp"

namespace hystbench::daemon::details {

namespace hc = compensation;
using nlohmann::json;

namespace {

// The compensator a result's design is for: inverse+pid with a model, pid without.
hc::CompensatorKind default_feedback(bool model) {
  return model ? hc::CompensatorKind::kInversePid : hc::CompensatorKind::kPid;
}

}  // namespace

FeedbackDesigner::FeedbackDesigner(BenchParts bench, ModelStore& models, RunHooks hooks)
    : bench_(bench), models_(models), hooks_(std::move(hooks)) {}

json FeedbackDesigner::start_frf(const RequestParams& request) {
  const RunContext ctx = hooks_.run_context();
  const sim::FrequencyResponseExcitationOptions o = response_options(request, ctx);
  json reply = bench_.runs.launch("frf", make_response_program(o, ctx));
  frf_options_ = o;
  return reply;
}

json FeedbackDesigner::tune(hc::CompensatorKind kind, const std::string& name,
                            const FeedbackGainsRequest& gains) {
  const FeedbackPlan plan = plan_feedback(hooks_.run_context(), kind, gains);
  json out = plan.summary;
  out["compensator"] = name;
  last_ = out;
  out["curves"] = loop_curves(plan, bench_.dt());
  return out;
}

json FeedbackDesigner::feedback_now(hc::CompensatorKind kind, json* why) {
  try {
    json f = plan_feedback(hooks_.run_context(), kind, {}).summary;
    f["compensator"] = std::string(hc::to_string(kind));
    last_ = f;
    return f;
  } catch (const std::exception& e) {
    if (why != nullptr) *why = e.what();
    return nullptr;
  }
}

void FeedbackDesigner::track_started(json feedback, const std::string& compensator) {
  last_ = std::move(feedback);
  last_["compensator"] = compensator;
}

void FeedbackDesigner::responses_measured(std::unique_ptr<RunProgram> run, RunResult result) {
  json& report = result.report;
  std::optional<sim::FrequencyResponseExcitationOptions> options;
  {
    std::lock_guard lock(bench_.mutex);
    options = std::move(frf_options_);
    frf_options_.reset();
  }
  if (run->end == RunEnd::kCompleted && options) {
    try {
      hc::StageResponses r = measure_responses(*run, *options);
      std::lock_guard lock(bench_.mutex);
      report["frequency_response"] = responses_summary(r, models_.design_responses());
      report["frequency_response"]["measured"] = hc::to_json(r);
      models_.keep_frf_responses(std::move(r), report["frequency_response"]);
      json why;
      report["feedback"] = feedback_now(default_feedback(models_.active() != nullptr), &why);
      if (report["feedback"].is_null()) report["feedback_error"] = why;
    } catch (const std::exception& e) {
      report["frequency_response_error"] = e.what();
      spdlog::error("run {}: the frequency response: {}", run->run_id, e.what());
    }
  } else {
    report["frequency_response_error"] = "the run did not complete: nothing was measured";
  }
  hooks_.deliver(std::move(report));
}

}  // namespace hystbench::daemon::details
