#pragma once
// What a finished run reports: its log closed, its outcome, counters, loop timing and error
// figures gathered into run.finished's "result" object. Pure apart from closing the log (no
// threads); supervisor thread. Not real-time safe.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

#include "hystbench/daemon/loop/run_program.hpp"

namespace hystbench::daemon::details {

struct RunResult {
  RunKind kind = RunKind::kTrack;
  RunEnd end = RunEnd::kCompleted;
  std::size_t recorded = 0;  ///< samples in the program's record (records.u, records.y)
  std::string log_path;      ///< empty without a log
  nlohmann::json report;     ///< run.finished's "result"

  /// identify ran to its end with a record long enough to fit.
  bool wants_fit() const noexcept {
    return kind == RunKind::kIdentify && end == RunEnd::kCompleted && recorded > 100;
  }
};

/// Closes the run's log (if any) and reports the run: id, kind, end and reason, samples,
/// logging, loop timing, limit counters, `output_v_after` [V], the run's summary, tracking
/// error (track) and the model's error on the bench [µm, %].
RunResult collect_result(RunProgram& run, double output_v_after);

}  // namespace hystbench::daemon::details
