#pragma once
// excite's run: a complete drive upload played open loop after a ramp from the present output
// within the slew limit, logged for fit and diagnose. Pure (no threads, no files); errors are
// CommandError naming the offending sample. Not real-time safe.
#include "hystbench/daemon/runs/upload_store.hpp"
#include "runs/details/run_context.hpp"

namespace hystbench::daemon::details {

/// The excite program for a complete drive upload [V], checked against the output limits.
BuiltRun make_excite_program(const Upload& drive_upload, const RunContext& ctx);

}  // namespace hystbench::daemon::details
