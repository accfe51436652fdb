#pragma once
// What the bench knows when a run starts (settings, active model, present output) and what a
// run builder returns: the program, its log header and the start reply's keys. The builders
// (track_program.hpp, identify_program.hpp, excite_program.hpp) are pure functions of these:
// no threads, no files, no loop; errors are CommandError naming the cause. Not real-time safe.
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/drive_planner.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/stage_responses.hpp"
#include "hystbench/daemon/config/bench_settings.hpp"
#include "hystbench/daemon/loop/run_program.hpp"
#include "runs/details/track_learning.hpp"

namespace hystbench::daemon::details {

struct FeedbackPlanCache;  // feedback_design.hpp
struct FeedbackPlan;       // feedback_design.hpp

/// The last feedforward plan and what it was planned from: a track run with the same model, the
/// same start (output, open-loop prefix) and the same targets (another compensator over the same
/// reference, as a sweep runs them) plays it again instead of planning it anew. The plan is a
/// deterministic function of these (the planner starts the model relaxed at the output, not from
/// its history), so the drive is the one a new plan would give. Any thread.
struct PlanCache {
  /// What a plan is made from.
  struct Inputs {
    std::uint64_t model_generation = 0;
    double u_now = 0.0;
    std::vector<double> excitation, targets;
    std::uint64_t planned_samples = 0;
    double period_samples = 0.0;
    bool operator==(const Inputs&) const = default;
  };
  std::mutex mutex;
  Inputs inputs;
  std::optional<compensation::DrivePlan> plan;  ///< empty: nothing kept
};

struct RunContext {
  const BenchSettings& settings;
  const compensation::ModelFile* model = nullptr;            ///< the active model, or null
  double u_now = 0.0;                                        ///< the loop's present output [V]
  double dt() const { return 1.0 / settings.loop.rate_hz; }  ///< loop period [s]
  /// Counts the bench's model changes: a plan kept for one generation is not another's.
  std::uint64_t model_generation = 0;
  /// Where track keeps its last plan; null = every plan is made anew.
  std::shared_ptr<PlanCache> plans = nullptr;
  /// The stage's frequency responses the bench measured last (frf, identify), null if none:
  /// the feedback's when the active model holds none.
  const compensation::StageResponses* responses = nullptr;
  /// Where the feedback's last design is kept; null = designed anew.
  std::shared_ptr<FeedbackPlanCache> feedback_plans = nullptr;
  /// The active model as the actuator's history leaves it now: stepped through the output of
  /// every tick the loop kept (ModelStateTracker), configured at dt(). Null where that is not
  /// known (no model, a stage, nothing played yet): a run's model then starts relaxed at u_now.
  std::shared_ptr<const compensation::ActuatorModel> model_state = nullptr;
  /// The output history model_state was stepped through [s] (0 without).
  double model_history_s = 0.0;
};

/// Thrown by a preparation's progress callback to cancel it (stop, abort, shutdown); not a
/// std::exception, so work that catches those lets it through.
struct PreparationCancelled {};

/// Work a run needs before the loop may start it, too long to hold the command's reply (track:
/// the feedforward planned over the reference, seconds). The bench calls `work` once, on its
/// supervisor thread, with the program (run id and log set); it completes the program (its
/// compensator, its summary) and calls `progress` with the fraction done (0..1), which throws
/// PreparationCancelled to cancel. Work that fails otherwise leaves the program as built (it
/// can run) and says why in its summary. Not real-time safe.
struct RunPreparation {
  std::string stage;  ///< what it does, for progress events and status ("planning ...")
  std::function<void(RunProgram&, const std::function<void(double)>& progress)> work;
};

/// A run ready for the loop: the program (its run id and log are the bench's to add), the run
/// log's header, the keys the bench adds to the start reply and to status' "run", and the
/// preparation before the loop may start it (none when `preparation.work` is empty).
struct BuiltRun {
  std::unique_ptr<RunProgram> program;
  nlohmann::json header;
  nlohmann::json reply = nlohmann::json::object();
  nlohmann::json status = nlohmann::json::object();
  /// identify: what the fit after the run needs (model, operators, dead_zones, skip_samples,
  /// precondition_s, settle_s); null otherwise.
  nlohmann::json fit;
  RunPreparation preparation;
  /// track --learn: the learner of the run's trials (it holds the program's exchange).
  std::unique_ptr<TrackLearning> learning;
  /// track --learn on a stage: the learners of axes 1, 2, ... (axis 0's is `learning`).
  std::vector<std::unique_ptr<TrackLearning>> axis_learning;
  /// track with feedback: the loop's design (a stage checks its axes' loops together).
  std::shared_ptr<const FeedbackPlan> feedback_plan;
};

/// Most samples a run records for its figures and fit (the log keeps every sample).
inline constexpr std::uint64_t kMaxRecordedSamples = 2'000'000;

/// The reference range [µm]: the active model's major loop over the output limits, else the
/// configured limits.y_min..y_max; nullopt when neither is known.
struct ActuatorRange {
  double y_bottom, y_top;
};
std::optional<ActuatorRange> actuator_range(const RunContext& ctx);

/// The run's predictor of y (RunProgram::model): the active model in the state its history left
/// (model_state), else relaxed at output u0; without a model the linear map of
/// limits.y_min/y_max; nullopt when neither is known.
std::optional<compensation::ActuatorModel> predictor(const RunContext& ctx, double u0);
/// The active model a run's inverse starts from after `prefix` (its open-loop sweep): from
/// model_state where known, else relaxed at u_now (model_after). Needs ctx.model.
compensation::ActuatorModel model_at_start(const RunContext& ctx, std::span<const double> prefix);
/// What predictor() gives, in words, for the log header.
const char* predictor_name(const RunContext& ctx);
/// Whose prediction predictor() gives, for a result's y_model_from: "model" (the active model),
/// "limits" (the straight line of limits.y_min/y_max, which measures nothing of the actuator) or
/// "none". Clients read it, not y_model's wording.
const char* predictor_source(const RunContext& ctx);
/// The run's predictor in its result: `y_model` (predictor_name), `y_model_from`
/// (predictor_source) and, with a model, where it starts: `model_start` "history" (model_state,
/// with `model_history_s`) or "relaxed" (at the run's first output).
void describe_predictor(const RunContext& ctx, nlohmann::json& summary);
/// The active model as a run log's header keeps it (its file without the stage's frequency
/// responses, which the model file keeps); null without one.
nlohmann::json model_header(const RunContext& ctx);

/// The driver exchange latency the active model's delay holds (its identification's
/// exchange_ticks; 0 for a model made elsewhere or none) [ticks].
std::uint64_t model_exchange_ticks(const RunContext& ctx);
/// The active model's input delay beyond that latency in whole ticks, rounded up (0 without).
std::uint64_t model_delay_ticks(const RunContext& ctx);

/// Appends a linear ramp from a to b over n samples (b on the last one) [V].
void append_ramp(std::vector<double>& out, double a, double b, std::size_t n);
/// Sizes the program's record from metrics_from to total_samples (at most
/// kMaxRecordedSamples); with `responses` the readings' response ticks too (identify).
void allocate_records(RunProgram& program, bool responses = false);

}  // namespace hystbench::daemon::details
