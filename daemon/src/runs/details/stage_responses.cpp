// A stage's frf: each axis's frequency responses measured in its own turn (stage_runs.hpp).
#include <algorithm>
#include <memory>
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

namespace {

// Axis `moved`'s turn as a run of its own, as measure_responses() reads one: its drive, and
// axis `seen`'s output.
std::unique_ptr<RunProgram> turn_record(const RunProgram& run, std::size_t moved, std::size_t seen,
                                        std::size_t turn) {
  const RunRecords& drive = run.axis(moved).records;
  const RunRecords& output = run.axis(seen).records;
  const std::size_t from = moved * turn;
  if (drive.count < from + turn || output.count < from + turn) {
    throw common::CommandError(
        "measurement_failed",
        "the stage's frf run ended before axis " + std::to_string(moved) + "'s turn was played");
  }
  auto alone = std::make_unique<RunProgram>();
  alone->run_id = run.run_id;
  alone->records.u.assign(drive.u.begin() + static_cast<std::ptrdiff_t>(from),
                          drive.u.begin() + static_cast<std::ptrdiff_t>(from + turn));
  alone->records.y.assign(output.y.begin() + static_cast<std::ptrdiff_t>(from),
                          output.y.begin() + static_cast<std::ptrdiff_t>(from + turn));
  alone->records.count = turn;
  alone->records.capacity = turn;
  return alone;
}

}  // namespace

std::vector<hc::StageResponses> measure_stage_responses(
    const RunProgram& run, std::span<const sim::FrequencyResponseExcitationOptions> options,
    std::size_t turn) {
  std::vector<hc::StageResponses> out;
  for (std::size_t a = 0; a < run.axes() && a < options.size(); ++a) {
    out.push_back(measure_responses(*turn_record(run, a, a, turn), options[a]));
  }
  return out;
}

std::vector<std::vector<hc::StageResponses>> measure_stage_cross_responses(
    const RunProgram& run, std::span<const sim::FrequencyResponseExcitationOptions> options,
    std::size_t turn) {
  const std::size_t n = std::min(run.axes(), options.size());
  std::vector<std::vector<hc::StageResponses>> cross(n, std::vector<hc::StageResponses>(n));
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      try {
        cross[i][j] = measure_responses(*turn_record(run, j, i, turn), options[j]);
      } catch (const std::exception&) {
        // Too little of axis j reaches axis i to measure: that pair stays empty.
      }
    }
  }
  return cross;
}

}  // namespace hystbench::daemon::details
