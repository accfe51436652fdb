#pragma once
// A run's sample log, opened before the loop plays the run. Not real-time safe (it creates the
// log file and its writer thread); the service calls it before it submits a run.
#include <nlohmann/json.hpp>

#include "hystbench/daemon/config/bench_settings.hpp"
#include "hystbench/daemon/loop/run_program.hpp"

namespace hystbench::daemon::details {

/// Opens p's log (p.log) in settings.log_dir with `header`; the header's run and p's result name
/// the loop's clock, and a run of several axes logs them under the settings' axis names. Throws
/// CommandError log_error naming the cause.
void open_run_log(RunProgram& p, nlohmann::json header, const BenchSettings& settings);

}  // namespace hystbench::daemon::details
