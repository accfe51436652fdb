// The identify coordinator's entry points: the excitation handed over, the segments handed back
// (identify_coordinator.hpp). The steps between them are in identify_*.cpp.
#include "service/details/identify_coordinator.hpp"

#include <exception>
#include <utility>

#include "service/details/identify_session.hpp"
#include "service/details/run_supervisor.hpp"

namespace hystbench::daemon::details {

IdentifyCoordinator::IdentifyCoordinator(BenchParts bench, Hooks hooks)
    : bench_(bench), dt_(bench.dt()), hooks_(std::move(hooks)) {}

IdentifyCoordinator::~IdentifyCoordinator() = default;

void IdentifyCoordinator::excitation_played(const RunProgram& run, RunResult result,
                                            const nlohmann::json& fit_request) {
  try {
    session_ = fit_candidates(run, result, fit_request);
    continue_identify();
    // The rest start once the first segment is on the loop (building its drive does not share
    // the second core with them).
    if (session_ && session_->step == IdentifyStep::kVerifyingCandidates) {
      diagnose_candidates_ahead(*session_);
    }
    return;
  } catch (const std::exception& e) {
    result.report["fit_error"] = e.what();
  }
  hooks_.deliver(std::move(result.report));
}

bool IdentifyCoordinator::owns(const RunProgram& run) const {
  return session_ && run.run_id == session_->program_id;
}

void IdentifyCoordinator::segment_played(std::unique_ptr<RunProgram> run) {
  if (session_->response_options) {
    responses_measured(std::move(run));
  } else {
    verification_finished(std::move(run));
  }
}

void IdentifyCoordinator::emit(const nlohmann::json& event) const { bench_.runs.emit(event); }

bool IdentifyCoordinator::quitting() const noexcept { return bench_.runs.quitting(); }

}  // namespace hystbench::daemon::details
