#pragma once
// The feedforward of a track run planned over its reference (compensation::plan_drive) as the
// run's preparation, on the bench's supervisor thread with progress, and the last plan kept for
// a run with the same inputs. Not real-time safe.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>

#include "hystbench/compensation/compensator.hpp"
#include "hystbench/compensation/feedback_controller.hpp"
#include "hystbench/daemon/loop/run_program.hpp"
#include "runs/details/run_context.hpp"

namespace hystbench::daemon::details {

/// The feedforward planned over the whole known reference for a rate-dependent model
/// (compensation::plan_drive: the per-sample rate law leaves a tick-by-tick inverse no good
/// choice at a fast reference's tops), as the run's preparation: the bench plans on its
/// supervisor thread, with progress, and the plan replaces the previewed inverse the program was
/// built with (for `inverse_multiplicative` too: its one-tick loop through the model trails a law
/// that lags the drive). No preparation, with the reason in `feedforward`, where the previewed
/// inverse stays: another model kind, a reference too long to plan in
/// kMaxPlanWork (a periodic one: its first four periods are planned and the third repeats); a plan
/// that is not better on the model, or that fails, also leaves it and says why in the run's result.
/// The targets are the loop's (TrackDrive::feedforward_target) without the tare, which the planned
/// inverse meets through the plan's gain once the prefix measured it.
RunPreparation feedforward_plan(const RunProgram& p, const RunContext& ctx,
                                compensation::CompensatorKind kind, std::uint64_t samples,
                                double reference_hz, nlohmann::json& feedforward,
                                const std::optional<compensation::FeedbackController>& pid,
                                const compensation::LinearMap& linear,
                                compensation::FeedbackPath path);

}  // namespace hystbench::daemon::details
