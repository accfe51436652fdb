#pragma once
// track's run: an open-loop precondition sweep, then a reference (built-in, or a user's
// trajectory) through the compensator the request names (none, inverse,
// inverse_multiplicative, inverse+pid, pid). Pure (no threads, no files); errors are
// CommandError naming the cause (bad_params, no_model, no_range, not_invertible, bad_model,
// out_of_range, slew_limit). Not real-time safe.
#include <memory>

#include "hystbench/daemon/runs/upload_store.hpp"
#include "hystbench/sim/signal_generator.hpp"
#include "runs/details/run_context.hpp"
#include "runs/details/track_reference.hpp"
#include "runs/details/track_request.hpp"

namespace hystbench::daemon::details {

/// The track program for a parsed request; `reference_upload` is the complete upload the
/// request names (TrackRequest::reference_upload), else null for a built-in one.
/// Units: the reference and its range in µm, the output in V, times in s.
BuiltRun make_track_program(const TrackRequest& request, const RunContext& ctx,
                            const Upload* reference_upload);

/// The reference make_track_program() would play for the request (a learning run's passes
/// too), over the range ctx's model gives: for a caller that needs it before the run (a stage's
/// decoupling).
TrackReference track_reference(const TrackRequest& request, const RunContext& ctx,
                               const Upload* reference_upload);

/// One axis of a stage's track: as make_track_program() with `axis_reference` built by
/// track_reference() for that axis from `reference_upload`, and the feedforward fed
/// `feedforward_reference` (the axis's target with the coupling taken out; null: the
/// reference). A learning run's learner is the BuiltRun's.
BuiltRun make_axis_track_program(const TrackRequest& request, const RunContext& ctx,
                                 const Upload* reference_upload, TrackReference axis_reference,
                                 std::unique_ptr<sim::SignalGenerator> feedforward_reference);

}  // namespace hystbench::daemon::details
