// The frf and tune commands: the request checked, then handed to the stage coordinator on a
// stage of several axes, else to the feedback designer (details/feedback_designer.hpp).
#include <mutex>

#include "hystbench/common/command_error.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "runs/details/feedback_design.hpp"
#include "runs/details/request_params.hpp"
#include "runs/details/run_context.hpp"
#include "runs/details/stage_runs.hpp"
#include "service/details/feedback_designer.hpp"
#include "service/details/model_store.hpp"
#include "service/details/stage_coordinator.hpp"

namespace hystbench::daemon {

namespace hc = compensation;
using nlohmann::json;

json Bench::start_frf(const details::RequestParams& request) {
  std::lock_guard lock(mutex_);
  require_idle();
  return is_stage() ? stage_->start_frf(request) : feedback_->start_frf(request);
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
  if (is_stage()) {
    json out = details::stage_tune(run_context(), stage_->model(), stage_->axis_outputs(),
                                   settings_.axes, *kind, gains);
    out["compensator"] = name;
    return out;
  }
  return feedback_->tune(*kind, name, gains);
}

}  // namespace hystbench::daemon
