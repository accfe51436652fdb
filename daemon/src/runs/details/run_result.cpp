#include "runs/details/run_result.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "hystbench/daemon/runs/track_drive.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

namespace {

// The simulation's error on the bench: y - y_model over the scored samples, in µm and in % of
// the output range the run covered (the reference's for a tracking run); its mean apart, an
// offset the model does not hold (the creep since identify, which a track's tare takes off).
void add_model_error(const RunProgram& run, json& report) {
  const std::size_t n = run.records.count;
  if (run.model_error.samples == 0 || n <= 2) return;
  const auto [lo, hi] = std::minmax_element(run.records.y.begin(), run.records.y.begin() + n);
  const double range = report.contains("range_um") ? report["range_um"].get<double>() : *hi - *lo;
  const double rms = run.model_error.rms();
  report["model_rms_error_um"] = rms;
  report["model_max_error_um"] = run.model_error.max;
  report["model_rms_error_percent"] = compensation::percent_of_range(rms, range);
  report["model_max_error_percent"] = compensation::percent_of_range(run.model_error.max, range);
  report["model_max_error_index"] = run.model_error.max_index;
  report["model_mean_error_um"] = run.model_error.mean();
}

// A drive learned before whose lead-in ended before its longest: the header's metrics_from is
// the latest the scored part could begin; a last comment line gives where it began.
void append_lead_in_end(const RunProgram& run, const std::string& path) {
  const TrackDrive* track = track_drive(run);
  const LearningExchange* learning = track != nullptr ? track->learning.get() : nullptr;
  if (learning == nullptr || learning->first_scored_tick() >= learning->first_tick) return;
  std::ofstream out(path, std::ios::app);
  out << "# "
      << nlohmann::json{{"scored_from", learning->first_scored_tick()},
                        {"lead_in_periods", learning->lead_in_played()}}
             .dump()
      << "\n";
}

}  // namespace

RunResult collect_result(RunProgram& run, double output_v_after) {
  RunResult r;
  r.kind = run.kind;
  r.end = run.end;
  r.recorded = run.records.count;
  SampleLogCounts counts;
  if (run.log) {
    r.log_path = run.log->path().string();
    counts = run.log->close();
    append_lead_in_end(run, r.log_path);
  }
  r.report = {{"run_id", run.run_id},
              {"kind", to_string(run.kind)},
              {"end", to_string(run.end)},
              {"reason", run.end_reason},
              {"samples", run.done.load()},
              {"planned_samples", run.total_samples},
              {"logged", counts.written},
              {"dropped", counts.dropped + run.counters.log_drops},
              {"log", r.log_path},
              {"loop", to_json(run.stats.snapshot())},
              {"overruns", run.counters.overruns},
              {"clamps", run.counters.clamps},
              {"slew_limits", run.counters.slew_limits},
              {"reference_clips", run.counters.reference_clips},
              {"stale_reads", run.counters.stale_reads},
              {"output_v_after", output_v_after}};
  if (!counts.error.empty()) r.report["log_error"] = counts.error;
  r.report.update(run.summary);
  if (run.kind == RunKind::kTrack) r.report.update(tracking_error_json(run));
  if (run.oscillation && run.oscillation->trip().tripped) {
    const OscillationTrip& t = run.oscillation->trip();
    r.report["oscillation"] = {{"kind", t.growing ? "growing" : "sustained"},
                               {"rms_um", t.rms_um},
                               {"frequency_hz", t.frequency_hz},
                               {"tick", t.tick}};
  }
  add_model_error(run, r.report);
  return r;
}

}  // namespace hystbench::daemon::details
