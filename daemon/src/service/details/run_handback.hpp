#pragma once
// The runs handed back to the bench on the supervisor thread: each run the loop played goes to
// the component that owns what comes after it (identify's segments and fit, a stage's fit and
// responses, frf's responses), else its result is made and delivered here; a run that ends
// before the loop played it is delivered with why. The learning runs see every result first.
// Takes the bench's mutex where it touches the run supervisor; never on the loop thread.
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "hystbench/daemon/loop/run_program.hpp"
#include "runs/details/run_result.hpp"
#include "service/details/bench_parts.hpp"

namespace hystbench::daemon::details {

class IdentifyCoordinator;
class LearningRuns;
class FeedbackDesigner;
class StageCoordinator;

class RunHandback {
 public:
  /// The components runs go to (each outlives the hand-back; `stage` null on one axis), and
  /// how a result is kept and announced (no lock held).
  struct Owners {
    IdentifyCoordinator& identify;
    LearningRuns& learning;
    FeedbackDesigner& feedback;
    StageCoordinator* stage = nullptr;
    std::function<void(nlohmann::json)> deliver;
  };

  RunHandback(BenchParts bench, Owners owners) : bench_(bench), owners_(std::move(owners)) {}

  /// identify's fit request (BuiltRun::fit) for the excitation now launched. Caller holds the
  /// bench's mutex.
  void expect_fit(nlohmann::json fit_request) { pending_fit_ = std::move(fit_request); }
  /// A run the loop played and handed back: to its owner, or its result delivered.
  void played(std::unique_ptr<RunProgram> run);
  /// A run that ended before the loop played it (stopped or aborted while it was prepared,
  /// refused by the loop): delivered with 0 samples and `reason`.
  void unplayed(std::unique_ptr<RunProgram> run, RunEnd end, const std::string& reason);

 private:
  /// The run's result made (a stage's per axis) and shown to its learners.
  RunResult collect(RunProgram& run);

  BenchParts bench_;
  Owners owners_;
  nlohmann::json pending_fit_;  // under the bench's mutex
};

}  // namespace hystbench::daemon::details
