#include "runs/details/track_feedforward_plan.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "hystbench/compensation/drive_planner.hpp"
#include "hystbench/compensation/planned_inverse.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "hystbench/daemon/runs/track_drive.hpp"

namespace hystbench::daemon::details {

namespace hc = compensation;
using nlohmann::json;

namespace {

/// Takes the kept plan into `plan` when it was made from the same inputs; true then.
bool reuse_plan(PlanCache& cache, const PlanCache::Inputs& inputs,
                std::optional<hc::DrivePlan>& plan) {
  std::lock_guard lock(cache.mutex);
  if (!cache.plan || !(cache.inputs == inputs)) return false;
  plan = cache.plan;
  return true;
}

/// Keeps `plan` and what it was made from, in place of the plan kept before.
void keep_plan(PlanCache& cache, PlanCache::Inputs inputs, const hc::DrivePlan& plan) {
  std::lock_guard lock(cache.mutex);
  cache.inputs = std::move(inputs);
  cache.plan = plan;
}

// The most planning a track run waits for before it starts, in compensation::plan_drive_work's
// units (120 000 samples, 12 s at 10 kHz, for a model of 6 plays); what that costs in seconds,
// hystbench-bench --benchmark_filter=plan_drive measures.
constexpr double kMaxPlanWork = 1.0e6;
// The previewed inverse's error on the model below which a plan is not worth its time, as a
// fraction of the reference's span.
constexpr double kGoodEnoughFraction = 1e-3;

// The work of feedforward_plan's preparation: the drive planned over the targets (or the plan
// kept from the same inputs), put in the program's compensator in place of the previewed
// inverse where it is better on the model; the program's summary says which and why.
struct FeedforwardPlanning {
  hc::ActuatorModel relaxed;  ///< the model relaxed at the present output u_now
  double u_now = 0.0;
  std::vector<double> targets;
  std::uint64_t planned_samples = 0;  ///< the targets planned; a periodic rest continues them
  double period_samples = 0.0;
  hc::CompensatorKind kind;
  std::optional<hc::FeedbackController> pid;
  hc::LinearMap linear;
  hc::FeedbackPath path = hc::FeedbackPath::kInverse;
  std::shared_ptr<PlanCache> cache;
  std::uint64_t generation = 0;  ///< the model's, for the cache

  void operator()(RunProgram& program, const std::function<void(double)>& progress) {
    hc::DrivePlanOptions options;
    options.progress = progress;
    // Below 0.1 % of the reference's span on the model the previewed inverse is kept:
    // the model's own mismatch with the actuator is larger than that (a slow reference).
    const auto [lo, hi] = std::minmax_element(targets.begin(), targets.end());
    options.accept_start_rms = kGoodEnoughFraction * (*hi - *lo);
    const auto start = std::chrono::steady_clock::now();
    json planned = {{"samples", 0}};
    std::optional<hc::DrivePlan> plan;
    const bool reused = cache && reuse_plan(*cache, inputs(program), plan);
    try {
      if (reused) {
        progress(1.0);  // a stop or abort meanwhile still cancels the run
      } else {
        make_plan(program, options, plan);
      }
    } catch (const PreparationCancelled&) {
      program.summary["feedforward"]["planned"] = {
          {"samples", 0}, {"why_not", "cancelled before the plan was done"}};
      throw;
    } catch (const std::exception& e) {
      planned["why_not"] =
          std::string("planning failed (") + e.what() + "): the previewed inverse follows it";
    }
    if (plan && plan->start_rms <= options.accept_start_rms) {
      planned["why_not"] = "the previewed inverse already meets the targets on the model (" +
                           std::to_string(plan->start_rms) +
                           " um rms, within 0.1 % of the reference's span): it follows them";
      plan.reset();
    }
    if (plan) {
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      adopt(program, *plan, reused, seconds, planned);
    }
    program.summary["feedforward"]["planned"] = planned;
  }

  // Plans the drive over the first planned_samples targets, continues a periodic plan over the
  // rest and keeps the plan in the cache.
  void make_plan(const RunProgram& program, const hc::DrivePlanOptions& options,
                 std::optional<hc::DrivePlan>& plan) {
    plan = hc::plan_drive(relaxed, u_now, program.excitation,
                          std::span<const double>(targets).first(planned_samples), options);
    if (planned_samples < targets.size()) {
      plan = hc::continue_periodic_plan(std::move(*plan), period_samples, targets.size());
    }
    if (cache) keep_plan(*cache, inputs(program), *plan);
  }

  // What this run's plan is made from, for the cache.
  PlanCache::Inputs inputs(const RunProgram& program) const {
    return {generation, u_now, program.excitation, targets, planned_samples, period_samples};
  }

  // Puts the plan in the program's compensator where it is better on the model than the
  // previewed inverse; `planned` gets its figures, or why it does not play.
  void adopt(RunProgram& program, hc::DrivePlan& plan, bool reused, double seconds, json& planned) {
    planned = {{"samples", targets.size()}, {"optimised_samples", planned_samples},
               {"seconds", seconds},        {"reused", reused},
               {"model_rms_um", plan.rms},  {"previewed_model_rms_um", plan.start_rms}};
    // The plan pays for its smoothness, and beyond the rates its model was identified
    // at it plans on the continued law: where that leaves it worse on the model as it
    // is, the previewed inverse plays.
    if (plan.rms <= plan.start_rms) {
      track_drive(program)->program.compensator.emplace(
          kind, std::make_unique<hc::PlannedInverse>(std::move(targets), std::move(plan)), pid,
          linear, path);
    } else {
      planned["samples"] = 0;
      planned["why_not"] = "on the model the plan's error (" + std::to_string(plan.rms) +
                           " um rms) is not below the previewed inverse's (" +
                           std::to_string(plan.start_rms) +
                           " um): the previewed inverse follows it";
    }
  }
};

// The samples of the reference the planner plans, and its period in samples (0: planned
// whole). A periodic reference too long to plan whole: its first four periods are planned and
// the third repeats (the model's state repeats with the reference after one period; not with
// creep, whose state drifts over the run).
std::pair<std::uint64_t, double> planned_window(const hc::ActuatorModel& model,
                                                std::uint64_t samples, double reference_hz,
                                                double dt) {
  if (hc::plan_drive_work(model, samples) > kMaxPlanWork && reference_hz > 0.0 && !model.creep()) {
    const double period_samples = 1.0 / (reference_hz * dt);
    return {std::min<std::uint64_t>(
                samples, static_cast<std::uint64_t>(std::ceil(4.0 * period_samples)) + 1),
            period_samples};
  }
  return {samples, 0.0};
}

}  // namespace

RunPreparation feedforward_plan(const RunProgram& p, const RunContext& ctx,
                                hc::CompensatorKind kind, std::uint64_t samples,
                                double reference_hz, json& feedforward,
                                const std::optional<hc::FeedbackController>& pid,
                                const hc::LinearMap& linear, hc::FeedbackPath path) {
  if (!hc::can_plan_drive(ctx.model->model) || samples == 0) return {};
  const auto& lim = ctx.settings.loop.limits;
  const double dt = ctx.dt();
  const auto [planned_samples, period_samples] =
      planned_window(ctx.model->model, samples, reference_hz, dt);
  if (hc::plan_drive_work(ctx.model->model, planned_samples) > kMaxPlanWork) {
    const auto longest =
        static_cast<std::uint64_t>(kMaxPlanWork / hc::plan_drive_work(ctx.model->model, 1));
    feedforward["planned"] = {
        {"samples", 0},
        {"why_not", "the reference (" + std::to_string(samples) +
                        " samples) is longer than the planner takes for this model (" +
                        std::to_string(longest) + "): the previewed inverse follows it"}};
    return {};
  }
  std::vector<double> targets(samples);
  const TrackProgram& track = track_drive(p)->program;
  for (std::uint64_t k = 0; k < samples; ++k) {
    targets[k] = track.feedforward_target(static_cast<double>(k) * dt, 0.0);
  }
  feedforward["planned"] = {{"samples", samples}, {"planning", true}};
  return {
      "planning the feedforward",
      FeedforwardPlanning{model_after(ctx.model->model, {}, ctx.u_now, lim.u_min, lim.u_max, dt),
                          ctx.u_now, std::move(targets), planned_samples, period_samples, kind, pid,
                          linear, path, ctx.plans, ctx.model_generation}};
}

}  // namespace hystbench::daemon::details
