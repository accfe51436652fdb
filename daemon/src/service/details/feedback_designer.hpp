#pragma once
// The feedback designer: on a bench of one axis, frf's runs and the responses they measure, and
// the feedback a track run gets, designed on them (runs/details/feedback_design.hpp) for a
// result, tune and status. identify's own measurement is the identify coordinator's; a stage's,
// the stage coordinator's. Commands come with the bench's mutex held; the supervisor thread's
// step (an frf run played) takes it where it touches the designer's or the model store's state.
// Never on the loop thread.
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "hystbench/compensation/compensator.hpp"
#include "hystbench/sim/frequency_response_excitation.hpp"
#include "runs/details/run_result.hpp"
#include "service/details/bench_parts.hpp"

namespace hystbench::daemon {
struct RunProgram;
}

namespace hystbench::daemon::details {

class RequestParams;
class ModelStore;
struct FeedbackGainsRequest;

class FeedbackDesigner {
 public:
  /// `models` is the bench's, and outlives the designer.
  FeedbackDesigner(BenchParts bench, ModelStore& models, RunHooks hooks);
  FeedbackDesigner(const FeedbackDesigner&) = delete;
  FeedbackDesigner& operator=(const FeedbackDesigner&) = delete;

  // Commands; the caller holds the bench's mutex.
  /// frf: the multisines that measure the responses, open loop. The bench is idle.
  nlohmann::json start_frf(const RequestParams& request);
  /// tune: the feedback a track run with `kind` (named `name`) would get, designed or the given
  /// gains checked, with its loop's curves; runs nothing.
  nlohmann::json tune(compensation::CompensatorKind kind, const std::string& name,
                      const FeedbackGainsRequest& gains);
  /// The feedback a track run with `kind` would get now, for a result (null when the bench cannot
  /// design one: `why` says so); kept for status.
  nlohmann::json feedback_now(compensation::CompensatorKind kind, nlohmann::json* why);
  /// A track run started with this feedback (its reply's), through `compensator`.
  void track_started(nlohmann::json feedback, const std::string& compensator);
  /// status' "feedback": the last track's, tune's or frf's design (null before one).
  const nlohmann::json& last() const noexcept { return last_; }

  /// The supervisor thread's step: an frf run played, its responses estimated and kept with the
  /// active model, the feedback designed on them; its result delivered.
  void responses_measured(std::unique_ptr<RunProgram> run, RunResult result);

 private:
  BenchParts bench_;
  ModelStore& models_;
  RunHooks hooks_;
  // Under the bench's mutex:
  std::optional<sim::FrequencyResponseExcitationOptions> frf_options_;  // the frf under way
  nlohmann::json last_;
};

}  // namespace hystbench::daemon::details
