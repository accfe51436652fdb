#include "service/details/run_handback.hpp"

#include <mutex>
#include <utility>

#include "runs/details/run_result.hpp"
#include "runs/details/stage_runs.hpp"
#include "service/details/feedback_designer.hpp"
#include "service/details/identify_coordinator.hpp"
#include "service/details/learning_runs.hpp"
#include "service/details/run_supervisor.hpp"
#include "service/details/stage_coordinator.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

RunResult RunHandback::collect(RunProgram& run) {
  {
    std::lock_guard lock(bench_.mutex);
    bench_.runs.finalizing();
  }
  RunResult result = collect_result(run, bench_.loop.last_output());
  // Its learners go with the program that holds their exchanges.
  if (run.axes() > 1) {
    replace_with_stage_result(result.report, run, bench_.settings.axes);
    owners_.learning.axes_finished(run, result.report);
  } else {
    owners_.learning.finished(run, result.report);
  }
  return result;
}

void RunHandback::unplayed(std::unique_ptr<RunProgram> run, RunEnd end, const std::string& reason) {
  run->end = end;
  RunResult result = collect(*run);
  result.report["reason"] = reason;
  owners_.deliver(std::move(result.report));
}

void RunHandback::played(std::unique_ptr<RunProgram> run) {
  if (owners_.identify.owns(*run)) {
    owners_.identify.segment_played(std::move(run));
    return;
  }
  RunResult result = collect(*run);
  const bool stage = run->axes() > 1;
  if (result.kind == RunKind::kFrequencyResponse) {
    if (stage) {
      owners_.stage->responses_measured(*run, std::move(result));
    } else {
      owners_.feedback.responses_measured(std::move(run), std::move(result));
    }
    return;
  }
  if (result.wants_fit()) {
    if (stage) {
      owners_.stage->identified(*run, std::move(result));
      return;
    }
    json fit_request;
    {
      std::lock_guard lock(bench_.mutex);
      fit_request = pending_fit_;
    }
    // Delivers when the candidates are verified.
    owners_.identify.excitation_played(*run, std::move(result), fit_request);
    return;
  }
  owners_.deliver(std::move(result.report));
}

}  // namespace hystbench::daemon::details
