#pragma once
// frf's run: the multisines that measure the stage's frequency responses in place
// (sim/frequency_response_excitation.hpp), open loop from the present output, logged like any
// run; and, once it has played, the responses estimated from its record (compensation's
// measured_response.hpp). identify plays the same run after its model is chosen. The
// excitation's options go into the responses' record (stage_responses.hpp) so that the drive
// can be played again through another model. Pure (no threads, no files); errors are
// CommandError. Not real-time safe.
#include <nlohmann/json.hpp>

#include "hystbench/compensation/stage_responses.hpp"
#include "hystbench/sim/frequency_response_excitation.hpp"
#include "runs/details/request_params.hpp"
#include "runs/details/run_context.hpp"

namespace hystbench::daemon::details {

/// The excitation's options: the bench's loop rate, limits and present output, the default
/// conditions unless the request sets `amplitude` (the small multisines' peak, a fraction of
/// the drive span) or `periods` (averaged).
sim::FrequencyResponseExcitationOptions response_options(const RequestParams& request,
                                                         const RunContext& ctx);
/// The same from nothing but the bench (identify's measurement).
sim::FrequencyResponseExcitationOptions response_options(const RunContext& ctx);

nlohmann::json to_json(const sim::FrequencyResponseExcitationOptions& o);
/// Throws CommandError bad_model naming the key when `j` is not such options.
sim::FrequencyResponseExcitationOptions response_options_from_json(const nlohmann::json& j);

/// The run: the excitation played open loop, every sample recorded.
BuiltRun make_response_program(const sim::FrequencyResponseExcitationOptions& o,
                               const RunContext& ctx);

/// The responses of a completed frf run (its record, the options it was built from). Throws
/// CommandError measurement_failed when the record is short or a line cannot be estimated.
compensation::StageResponses measure_responses(const RunProgram& run,
                                               const sim::FrequencyResponseExcitationOptions& o);

/// A short account of measured responses for a run's result: per response its label, its
/// low-frequency gain, the lowest coherence and the output's noise; the modes found; and,
/// against `before` (the responses measured earlier, null if none), how far the gain and the
/// leading mode moved.
nlohmann::json responses_summary(const compensation::StageResponses& r,
                                 const compensation::StageResponses* before);

}  // namespace hystbench::daemon::details
