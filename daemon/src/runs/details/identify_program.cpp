#include "runs/details/identify_program.hpp"

#include <cmath>
#include <string>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/fit_families.hpp"
#include "hystbench/sim/identification_excitation.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

namespace {

// A rate law is identified only up to the rates its record holds: for a family that fits one
// the excitation adds kRateLawCycles at kRateLawFrequencyHz over the rate segments' span, which
// covers a 19 Hz sine over 80 % of the range. A rate-free fit gains nothing from them but a bias
// towards fast loops, so the other families go without.
constexpr double kRateLawFrequencyHz = 20.0;
constexpr int kRateLawCycles = 20;

void add_rate_law_segment(sim::IdentificationExcitationOptions& options, const std::string& model,
                          double loop_rate_hz) {
  if (model != "rpi" && model != "auto") return;
  if (kRateLawFrequencyHz > loop_rate_hz / 20.0) return;  // too few samples per cycle
  for (const double f : options.rate_frequencies_hz) {
    if (f >= kRateLawFrequencyHz) return;
  }
  options.rate_frequencies_hz.push_back(kRateLawFrequencyHz);
  options.rate_cycles.push_back(kRateLawCycles);
}

}  // namespace

sim::Excitation identify_excitation(const IdentifyRequest& request, const RunContext& ctx) {
  const BenchSettings& s = ctx.settings;
  try {
    sim::IdentificationExcitationOptions options = s.identify_excitation;
    add_rate_law_segment(options, request.model, s.loop.rate_hz);
    options.major_loop_frequency_hz = s.identify.frequency_hz;
    options.major_loop_cycles = s.identify.cycles;
    options.precondition_s = s.identify.precondition_s;
    options.settle_s = s.identify.settle_s;
    options.reversals_last = true;  // the held-out end of the record: loop shape, not creep
    return sim::identification_excitation(request.u_min, request.u_max, ctx.dt(), options);
  } catch (const std::exception& e) {
    throw common::CommandError("bad_params", e.what());
  }
}

IdentifyRequest parse_identify_request(const RequestParams& request,
                                       const BenchSettings& settings) {
  const auto& lim = settings.loop.limits;
  IdentifyRequest r;
  r.model = request.string("model", settings.identify.model);
  if (!common::is_fit_family(r.model)) {
    throw common::CommandError(
        "bad_params", "model: unknown '" + r.model + "' (" + common::fit_family_names() + ")");
  }
  r.family_fixed = request.has("model") && r.model != "auto";
  r.operators = request.integer("operators", settings.identify.operators);
  r.dead_zones = request.integer("dead_zones", settings.identify.dead_zones);
  r.extend = request.boolean("extend", settings.identify.extend);
  const auto [u_min, u_max] = settings.identify.span_v(lim.u_min, lim.u_max);
  r.u_min = request.number("u_min", u_min, lim.u_min, lim.u_max);
  r.u_max = request.number("u_max", u_max, lim.u_min, lim.u_max);
  if (!(r.u_max > r.u_min))
    throw common::CommandError("bad_params", "u_max must be greater than u_min");
  return r;
}

BuiltRun make_identify_program(const IdentifyRequest& request, const RunContext& ctx) {
  const BenchSettings& s = ctx.settings;
  const sim::Excitation exc = identify_excitation(request, ctx);
  auto p = std::make_unique<RunProgram>();
  p->kind = RunKind::kIdentify;
  p->response_delay_ticks = model_delay_ticks(ctx);
  // Start from where the output is: a short ramp to the excitation's first value.
  append_ramp(p->excitation, ctx.u_now, exc.samples.front(),
              static_cast<std::size_t>(std::ceil(0.1 / ctx.dt())));
  p->model = predictor(ctx, ctx.u_now);
  // The result's model_rms_error is this predictor's: not the model identified from the run.
  describe_predictor(ctx, p->summary);
  if (ctx.model != nullptr) p->summary["y_model"] = "the model active before this identification";
  const std::size_t offset = p->excitation.size();
  p->excitation.insert(p->excitation.end(), exc.samples.begin(), exc.samples.end());
  p->total_samples = p->excitation.size();
  // Recorded from the first sample: the fit simulates the ramp, settle and sweep from
  // where the output was, so its model enters the scored part in the actuator's state.
  p->metrics_from = 0;
  const sim::ExcitationSegment* first_scored = exc.find("major_loop");
  const std::size_t skip = offset + (first_scored != nullptr ? first_scored->begin : 0);
  p->model_metrics_from = skip;
  allocate_records(*p, true);

  json segments = json::array();
  for (const auto& seg : exc.segments) {
    segments.push_back(
        {{"name", seg.name}, {"begin", seg.begin + offset}, {"end", seg.end + offset}});
  }
  BuiltRun run;
  run.program = std::move(p);
  run.header = {{"run",
                 {{"kind", "identify"},
                  {"model", request.model},
                  {"operators", request.operators},
                  {"dead_zones", request.dead_zones},
                  {"u_min", request.u_min},
                  {"u_max", request.u_max},
                  {"rate_hz", s.loop.rate_hz},
                  {"segments", segments}}},
                {"driver", s.driver_type},
                {"y_model", predictor_name(ctx)}};
  run.fit = {{"model", request.model},
             {"operators", request.operators},
             {"dead_zones", request.dead_zones},
             {"extend", request.extend},
             {"family_fixed", request.family_fixed},
             {"skip_samples", skip},
             {"precondition_s", s.identify.precondition_s},
             {"settle_s", s.identify.settle_s}};
  return run;
}

}  // namespace hystbench::daemon::details
