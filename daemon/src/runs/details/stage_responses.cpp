// A stage's frf: each axis's frequency responses measured in its own turn (stage_runs.hpp).
#include <algorithm>
#include <string>

#include "hystbench/common/command_error.hpp"
#include "runs/details/response_program.hpp"
#include "runs/details/stage_runs.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;
namespace hc = hystbench::compensation;

BuiltRun make_stage_response_program(
    std::span<const sim::FrequencyResponseExcitationOptions> options, const RunContext& ctx,
    std::span<const std::string> axes, std::span<const double> u_now) {
  std::vector<BuiltRun> turns;
  std::size_t turn = 0;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    turns.push_back(make_response_program(options[a], axis_context(ctx, nullptr, a, u_now[a])));
    turn = std::max<std::size_t>(turn, turns.back().program->excitation.size());
  }
  const std::size_t total = turn * axes.size();
  if (total > kMaxRecordedSamples) {
    throw common::CommandError("bad_params", "frf on a stage of " + std::to_string(axes.size()) +
                                                 " axes lasts " + std::to_string(total) +
                                                 " ticks, more than the bench records");
  }
  BuiltRun run;
  json per_axis = json::object();
  for (std::size_t a = 0; a < axes.size(); ++a) {
    std::unique_ptr<RunProgram> p = std::move(turns[a].program);
    // In its turn the axis plays its multisines; before it, it holds where it is; after it,
    // where they left it.
    std::vector<double> u(turn * a, u_now[a]);
    u.insert(u.end(), p->excitation.begin(), p->excitation.end());
    u.resize(total, p->excitation.back());
    p->excitation = std::move(u);
    p->total_samples = total;
    allocate_records(*p);
    per_axis[axes[a]] = turns[a].header["run"];
    if (a == 0) {
      run.program = std::move(p);
    } else {
      run.program->stage_axes.push_back(std::move(p));
    }
  }
  run.header = {{"run",
                 {{"kind", "frf"},
                  {"axes", std::vector<std::string>(axes.begin(), axes.end())},
                  {"turn_samples", turn},
                  {"rate_hz", ctx.settings.loop.rate_hz},
                  {"metrics_from", 0}}},
                {"driver", ctx.settings.driver_type},
                {"axes", per_axis}};
  run.reply = {{"axes", std::vector<std::string>(axes.begin(), axes.end())},
               {"one_axis_at_a_time", true},
               {"turn_s", static_cast<double>(turn) * ctx.dt()}};
  run.fit = {{"turn_samples", turn}};
  return run;
}

std::vector<hc::StageResponses> measure_stage_responses(
    const RunProgram& run, std::span<const sim::FrequencyResponseExcitationOptions> options,
    std::size_t turn) {
  std::vector<hc::StageResponses> out;
  for (std::size_t a = 0; a < run.axes() && a < options.size(); ++a) {
    const RunRecords& all = run.axis(a).records;
    const std::size_t from = a * turn;
    if (all.count < from + turn) {
      throw common::CommandError(
          "measurement_failed",
          "the stage's frf run ended before axis " + std::to_string(a) + "'s turn was played");
    }
    // The axis's turn as a run of its own, as measure_responses() reads one.
    RunProgram alone;
    alone.run_id = run.run_id;
    alone.records.u.assign(all.u.begin() + static_cast<std::ptrdiff_t>(from),
                           all.u.begin() + static_cast<std::ptrdiff_t>(from + turn));
    alone.records.y.assign(all.y.begin() + static_cast<std::ptrdiff_t>(from),
                           all.y.begin() + static_cast<std::ptrdiff_t>(from + turn));
    alone.records.count = turn;
    alone.records.capacity = turn;
    out.push_back(measure_responses(alone, options[a]));
  }
  return out;
}

}  // namespace hystbench::daemon::details
