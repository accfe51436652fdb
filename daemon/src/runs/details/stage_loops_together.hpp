#pragma once
// A stage's feedback loops checked together (compensation/stage_interaction.hpp): each axis's
// loop is designed alone on its own responses, then the coupling's cross responses tell
// whether they are stable together; where not, every loop's gain is lowered by one factor.
// Not real-time safe (the track run's builder, a command's thread).
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "hystbench/compensation/compensator.hpp"
#include "runs/details/feedback_design.hpp"
#include "runs/details/run_context.hpp"
#include "runs/details/stage_runs.hpp"

namespace hystbench::daemon::details {

/// The axes' loops designed for the coupling: each axis's loop designed on its own responses
/// (kept in its context's cache, where its track program takes it), then checked together; where
/// the check passes the limit, every loop's gain is lowered by the one factor (bisection) that
/// brings it back under, their margins checked again. Null without a loop on every axis or
/// cross responses; else what it did. Gains given by hand run as given (the check reports
/// them). Throws CommandError no_design when not even a fiftieth of the designed gain passes.
nlohmann::json design_loops_together(compensation::CompensatorKind kind,
                                     const FeedbackGainsRequest& gains,
                                     std::vector<RunContext>& contexts, const StageModel* stage,
                                     double dt);

/// The axes' loops checked together, as they run; null without a loop on every axis, or
/// without cross responses.
nlohmann::json feedback_interaction(const StageModel* stage,
                                    const std::vector<std::shared_ptr<const FeedbackPlan>>& plans,
                                    double dt);

}  // namespace hystbench::daemon::details
