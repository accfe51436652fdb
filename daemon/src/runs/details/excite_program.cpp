#include "runs/details/excite_program.hpp"

#include <algorithm>
#include <cmath>

#include "runs/details/track_reference.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

BuiltRun make_excite_program(const Upload& upload, const RunContext& ctx) {
  const BenchSettings& s = ctx.settings;
  const auto& lim = s.loop.limits;
  const std::vector<double> drive =
      checked_drive(upload, lim.u_min, lim.u_max, lim.slew_v_per_s, ctx.dt());

  auto p = std::make_unique<RunProgram>();
  p->kind = RunKind::kExcite;
  p->response_delay_ticks = model_delay_ticks(ctx);
  // From where the output is to the drive's first value within the slew limit (at least 0.1 s),
  // logged like the rest: the record starts from a known output.
  const double ramp_s = std::max(0.1, 2.0 * std::abs(drive.front() - ctx.u_now) / lim.slew_v_per_s);
  append_ramp(p->excitation, ctx.u_now, drive.front(),
              static_cast<std::size_t>(std::ceil(ramp_s / ctx.dt())));
  const std::size_t offset = p->excitation.size();
  p->excitation.insert(p->excitation.end(), drive.begin(), drive.end());
  p->model = predictor(ctx, ctx.u_now);
  describe_predictor(ctx, p->summary);
  p->total_samples = p->excitation.size();
  p->metrics_from = offset;
  allocate_records(*p);

  BuiltRun run;
  run.header = {{"run",
                 {{"kind", "excite"},
                  {"source", upload.source},
                  {"upload_samples", upload.values.size()},
                  {"ramp_samples", offset},
                  {"metrics_from", p->metrics_from},
                  {"u_min", *std::min_element(drive.begin(), drive.end())},
                  {"u_max", *std::max_element(drive.begin(), drive.end())},
                  {"rate_hz", s.loop.rate_hz}}},
                {"driver", s.driver_type},
                {"y_model", predictor_name(ctx)},
                {"model", model_header(ctx)}};
  run.reply = {{"drive_samples", drive.size()}, {"ramp_samples", offset}};
  run.program = std::move(p);
  return run;
}

}  // namespace hystbench::daemon::details
