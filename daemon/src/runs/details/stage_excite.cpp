#include <algorithm>
#include <string>

#include "hystbench/common/command_error.hpp"
#include "runs/details/excite_program.hpp"
#include "runs/details/stage_runs.hpp"

namespace hystbench::daemon::details {

using common::CommandError;
using nlohmann::json;

BuiltRun make_stage_excite_program(std::span<const Upload* const> drives, const RunContext& ctx,
                                   const StageModel* stage, std::span<const std::string> axes,
                                   std::span<const double> u_now) {
  const std::size_t n = u_now.size();
  std::vector<BuiltRun> axis_runs;
  std::size_t longest = 0;
  for (std::size_t a = 0; a < n; ++a) {
    try {
      axis_runs.push_back(make_excite_program(*drives[a], axis_context(ctx, stage, a, u_now[a])));
    } catch (const CommandError& e) {
      throw CommandError(e.code(), "axis " + axes[a] + "'s drive: " + e.what());
    }
    longest = std::max(longest, axis_runs.back().program->excitation.size());
  }
  if (longest > kMaxRecordedSamples) {
    throw CommandError("bad_params", "drive_uploads: the longest drive lasts " +
                                         std::to_string(longest) +
                                         " ticks with its ramp, more than the bench records");
  }
  BuiltRun run;
  json per_axis = json::object(), replies = json::object();
  for (std::size_t a = 0; a < n; ++a) {
    std::unique_ptr<RunProgram> p = std::move(axis_runs[a].program);
    // An axis whose drive ends first holds its last value while the others play on.
    p->excitation.resize(longest, p->excitation.back());
    p->total_samples = longest;
    allocate_records(*p);
    per_axis[axes[a]] = axis_runs[a].header["run"];
    replies[axes[a]] = axis_runs[a].reply;
    if (a == 0) {
      run.program = std::move(p);
    } else {
      run.program->stage_axes.push_back(std::move(p));
    }
  }
  if (stage != nullptr && stage->decoupler.axes() == n) run.program->coupling = stage->decoupler;
  run.header = {{"run",
                 {{"kind", "excite"},
                  {"axes", std::vector<std::string>(axes.begin(), axes.end())},
                  {"rate_hz", ctx.settings.loop.rate_hz},
                  {"metrics_from", run.program->metrics_from}}},
                {"driver", ctx.settings.driver_type},
                {"axes", per_axis}};
  run.reply = {{"axes", replies}};
  return run;
}

}  // namespace hystbench::daemon::details
