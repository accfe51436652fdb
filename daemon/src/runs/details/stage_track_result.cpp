// A stage's track result: each axis's figures under `axes`, and the coupling left (stage_runs.hpp).
#include <cmath>
#include <string>

#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/compensation/stage_coupling_error.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "runs/details/run_result.hpp"
#include "runs/details/stage_runs.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;
namespace hc = hystbench::compensation;

void replace_with_stage_result(json& report, const RunProgram& run,
                               std::span<const std::string> axes) {
  // The first axis's figures, which collect_result() put at the top, belong under `axes`.
  for (const char* key :
       {"rms_error_um", "max_error_um", "max_error_index", "range_um", "rms_error_percent",
        "max_error_percent", "hysteresis_percent", "error_samples", "tare_um", "startup_offset_um",
        "step", "model_rms_error_um", "model_max_error_um", "model_rms_error_percent",
        "model_max_error_percent", "model_max_error_index", "model_mean_error_um", "feedback",
        "feedforward"}) {
    report.erase(key);
  }
  report.update(stage_result(run, axes));
}

json stage_result(const RunProgram& run, std::span<const std::string> axes) {
  json per_axis = json::object();
  for (std::size_t a = 0; a < run.axes() && a < axes.size(); ++a) {
    const RunProgram& p = run.axis(a);
    json r = run.kind == RunKind::kTrack ? tracking_error_json(p) : json::object();
    // identify's prediction is the configured range's linear map, not a model: left out.
    if (run.kind == RunKind::kTrack && p.model_error.samples > 0) {
      r["model_rms_error_um"] = p.model_error.rms();
      r["model_max_error_um"] = p.model_error.max;
      r["model_mean_error_um"] = p.model_error.mean();
    }
    // What the axis's compensator was built with (its feedforward's plan, its loop's design).
    for (const char* key : {"feedforward", "feedback"}) {
      if (p.summary.contains(key)) r[key] = p.summary[key];
    }
    r["clamps"] = p.counters.clamps;
    r["slew_limits"] = p.counters.slew_limits;
    r["reference_clips"] = p.counters.reference_clips;
    per_axis[axes[a]] = std::move(r);
  }
  json out = {{"axes", per_axis}};
  if (run.kind != RunKind::kTrack || run.axes() < 2) return out;
  std::size_t samples = run.records.count;
  for (std::size_t a = 0; a < run.axes(); ++a)
    samples = std::min(samples, run.axis(a).records.count);
  if (samples < 10) return out;
  const auto n = static_cast<Eigen::Index>(run.axes());
  Eigen::MatrixXd errors(n, static_cast<Eigen::Index>(samples));
  Eigen::MatrixXd outputs(n, static_cast<Eigen::Index>(samples));
  for (Eigen::Index a = 0; a < n; ++a) {
    const RunRecords& rec = run.axis(static_cast<std::size_t>(a)).records;
    for (std::size_t k = 0; k < samples; ++k) {
      errors(a, static_cast<Eigen::Index>(k)) = rec.y[k] - rec.yr[k];
      outputs(a, static_cast<Eigen::Index>(k)) = rec.y[k];
    }
  }
  hc::CouplingErrorLeft left;
  try {
    left = hc::coupling_error_left(errors, outputs);
  } catch (const std::exception& e) {
    out["coupling_error"] = {{"why_not", e.what()}};
    return out;
  }
  json coupling = json::object();
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::string& name = axes[static_cast<std::size_t>(i)];
    const double range = per_axis[name].value("range_um", 0.0);
    json from = json::object();
    for (Eigen::Index j = 0; j < n; ++j) {
      if (i != j) from[axes[static_cast<std::size_t>(j)]] = left.gains(i, j);
    }
    coupling[name] = {{"rms_um", left.rms_um(i)},
                      {"rms_percent", compensation::percent_of_range(left.rms_um(i), range)},
                      {"gain_from", from}};
  }
  out["coupling_error"] = coupling;
  out["coupling_error_meaning"] =
      "per axis, the part of its tracking error the other axes' motion explains (its error "
      "regressed on their outputs over the scored samples), and the gains of that regression";
  return out;
}

}  // namespace hystbench::daemon::details
