#include "runs/details/response_program.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <span>

#include "hystbench/common/command_error.hpp"
#include "hystbench/compensation/measured_modes.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::daemon::details {

namespace hc = compensation;
using nlohmann::json;

sim::FrequencyResponseExcitationOptions response_options(const RunContext& ctx) {
  const auto& lim = ctx.settings.loop.limits;
  sim::FrequencyResponseExcitationOptions o;
  o.rate_hz = ctx.settings.loop.rate_hz;
  o.u_min = lim.u_min;
  o.u_max = lim.u_max;
  o.u_start = ctx.u_now;
  o.slew_v_per_s = lim.slew_v_per_s > 0.0 ? lim.slew_v_per_s : o.slew_v_per_s;
  o.precondition_s = ctx.settings.precondition_s;
  return o;
}

sim::FrequencyResponseExcitationOptions response_options(const RequestParams& request,
                                                         const RunContext& ctx) {
  sim::FrequencyResponseExcitationOptions o = response_options(ctx);
  if (request.has("amplitude")) {
    const double a = request.number("amplitude");
    // The small multisines at `a`, the last (the larger one) at four times it.
    for (std::size_t i = 0; i < o.conditions.size(); ++i) {
      o.conditions[i].amplitude_fraction =
          i + 1 == o.conditions.size() ? std::min(0.5, 4.0 * a) : a;
    }
  }
  o.periods = static_cast<std::size_t>(request.integer("periods", static_cast<int>(o.periods)));
  return o;
}

json to_json(const sim::FrequencyResponseExcitationOptions& o) {
  json conditions = json::array();
  for (const auto& c : o.conditions) {
    conditions.push_back({{"operating_fraction", c.operating_fraction},
                          {"amplitude_fraction", c.amplitude_fraction}});
  }
  return {{"rate_hz", o.rate_hz},
          {"u_min", o.u_min},
          {"u_max", o.u_max},
          {"u_start", o.u_start},
          {"slew_v_per_s", std::isfinite(o.slew_v_per_s) ? json(o.slew_v_per_s) : json(nullptr)},
          {"precondition_s", o.precondition_s},
          {"conditions", conditions},
          {"periods", o.periods},
          {"transient_periods", o.transient_periods},
          {"lines", o.lines},
          {"top_fraction", o.top_fraction},
          {"move_s", o.move_s},
          {"hold_s", o.hold_s},
          {"moving",
           {{"tone_fraction", o.moving_tone_fraction},
            {"cycles", o.moving_cycles},
            {"ramps", o.moving_ramps},
            {"from", o.moving_from},
            {"to", o.moving_to}}}};
}

sim::FrequencyResponseExcitationOptions response_options_from_json(const json& j) {
  sim::FrequencyResponseExcitationOptions o;
  try {
    o.rate_hz = j.at("rate_hz").get<double>();
    o.u_min = j.at("u_min").get<double>();
    o.u_max = j.at("u_max").get<double>();
    o.u_start = j.at("u_start").get<double>();
    if (!j.at("slew_v_per_s").is_null()) o.slew_v_per_s = j.at("slew_v_per_s").get<double>();
    o.precondition_s = j.at("precondition_s").get<double>();
    o.conditions.clear();
    for (const json& c : j.at("conditions")) {
      o.conditions.push_back(
          {c.at("operating_fraction").get<double>(), c.at("amplitude_fraction").get<double>()});
    }
    o.periods = j.at("periods").get<std::size_t>();
    o.transient_periods = j.at("transient_periods").get<std::size_t>();
    o.lines = j.at("lines").get<std::size_t>();
    o.top_fraction = j.at("top_fraction").get<double>();
    o.move_s = j.at("move_s").get<double>();
    o.hold_s = j.at("hold_s").get<double>();
    // Files from before the moving part: their drive had none.
    o.moving_tone_fraction = 0.0;
    if (j.contains("moving")) {
      const json& m = j["moving"];
      o.moving_tone_fraction = m.at("tone_fraction").get<double>();
      o.moving_cycles = m.at("cycles").get<std::size_t>();
      o.moving_ramps = m.at("ramps").get<std::size_t>();
      o.moving_from = m.at("from").get<double>();
      o.moving_to = m.at("to").get<double>();
    }
  } catch (const json::exception& e) {
    throw common::CommandError("bad_model",
                               std::string("frequency_response.excitation: ") + e.what());
  }
  return o;
}

BuiltRun make_response_program(const sim::FrequencyResponseExcitationOptions& o,
                               const RunContext& ctx) {
  sim::FrequencyResponseExcitation x;
  try {
    x = sim::make_frequency_response_excitation(o);
  } catch (const std::invalid_argument& e) {
    throw common::CommandError("bad_params", e.what());
  }
  auto p = std::make_unique<RunProgram>();
  p->kind = RunKind::kFrequencyResponse;
  p->response_delay_ticks = model_delay_ticks(ctx);
  p->excitation = std::move(x.u);
  p->model = predictor(ctx, ctx.u_now);
  describe_predictor(ctx, p->summary);
  p->total_samples = p->excitation.size();
  p->metrics_from = 0;
  allocate_records(*p);
  json segments = json::array();
  for (const auto& s : x.segments) {
    segments.push_back({{"label", s.label},
                        {"first", s.first},
                        {"periods", s.periods},
                        {"operating_point_v", s.operating_point_v},
                        {"amplitude_v", s.amplitude_v}});
  }
  BuiltRun run;
  run.header = {{"run",
                 {{"kind", "frf"},
                  {"rate_hz", ctx.settings.loop.rate_hz},
                  {"period_samples", x.period},
                  {"lines", x.lines.size()},
                  {"segments", segments},
                  {"metrics_from", 0}}},
                {"driver", ctx.settings.driver_type},
                {"y_model", predictor_name(ctx)}};
  run.reply = {{"conditions", segments.size()},
               {"lines", x.lines.size()},
               {"resolution_hz", o.rate_hz / static_cast<double>(x.period)}};
  run.program = std::move(p);
  return run;
}

namespace {

// Readings at the segment's extreme repeated bit for bit this often (and at least kClipSamples
// times) are a sensor or converter at the end of its range: the stage's answer is not in them.
constexpr double kClipShare = 0.002;
constexpr std::size_t kClipSamples = 3;

// The level the output clipped at over y, or nullopt.
std::optional<double> clip_level(std::span<const double> y) {
  const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
  const auto needed = std::max(kClipSamples, static_cast<std::size_t>(kClipShare * y.size()));
  for (const double level : {*lo, *hi}) {
    if (static_cast<std::size_t>(std::count(y.begin(), y.end(), level)) >= needed) return level;
  }
  return std::nullopt;
}

// The moving part's response; nullopt where the output clipped on a ramp (the stage's answer is
// not in it). Throws CommandError measurement_failed for a short record.
std::optional<hc::MovingResponse> moving_response(const RunProgram& run,
                                                  const sim::FrequencyResponseExcitation& x,
                                                  std::size_t n, double rate_hz) {
  for (const hc::MovingRamp& r : x.moving.ramps) {
    if (r.first + r.length > n) {
      throw common::CommandError("measurement_failed",
                                 "the run recorded " + std::to_string(n) +
                                     " samples, short of the moving ramps (up to sample " +
                                     std::to_string(r.first + r.length) + ")");
    }
    if (clip_level(std::span(run.records.y).subspan(r.first, r.length))) return std::nullopt;
  }
  try {
    return hc::estimate_moving_response(std::span(run.records.u).first(n),
                                        std::span(run.records.y).first(n), x.moving.ramps,
                                        x.moving.tone_hz, rate_hz);
  } catch (const std::invalid_argument& e) {
    throw common::CommandError("measurement_failed", std::string("the moving ramps: ") + e.what());
  }
}

}  // namespace

hc::StageResponses measure_responses(const RunProgram& run,
                                     const sim::FrequencyResponseExcitationOptions& o) {
  const sim::FrequencyResponseExcitation x = sim::make_frequency_response_excitation(o);
  const std::size_t n = std::min<std::size_t>(run.records.count, run.records.u.size());
  hc::StageResponses out;
  out.rate_hz = o.rate_hz;
  out.run_id = run.run_id;
  out.excitation = to_json(o);
  std::string clipped;
  for (const sim::ResponseMeasurementSegment& s : x.segments) {
    const std::size_t length = x.period * s.periods;
    if (s.first + length > n) {
      throw common::CommandError("measurement_failed", "the run recorded " + std::to_string(n) +
                                                           " samples, short of " + s.label +
                                                           " (up to sample " +
                                                           std::to_string(s.first + length) + ")");
    }
    const std::span<const double> y = std::span(run.records.y).subspan(s.first, length);
    if (const auto level = clip_level(y)) {
      clipped +=
          (clipped.empty() ? "" : "; ") + s.label + " at " + hc::significant(*level, 4) + " um";
      continue;
    }
    try {
      hc::MeasuredResponse r = hc::estimate_response(
          std::span(run.records.u).subspan(s.first, length), y, x.period, x.lines, o.rate_hz);
      r.operating_point = s.operating_point_v;
      r.amplitude = s.amplitude_v;
      r.label = s.label;
      out.responses.push_back(std::move(r));
      out.segments.push_back({s.first, x.period, s.periods});
    } catch (const std::invalid_argument& e) {
      throw common::CommandError("measurement_failed", s.label + ": " + e.what());
    }
  }
  if (!x.moving.ramps.empty()) out.moving = moving_response(run, x, n, o.rate_hz);
  if (out.responses.empty()) {
    throw common::CommandError(
        "measurement_failed",
        "the output clipped in every condition (" + clipped +
            "): the reading repeats its extreme, the sensor's or converter's end of range; the "
            "stage's answer to the multisines leaves it (lower frf's amplitude)");
  }
  if (!clipped.empty()) out.excitation["left_out"] = "the output clipped: " + clipped;
  return out;
}

json responses_summary(const hc::StageResponses& r, const hc::StageResponses* before) {
  json list = json::array();
  for (const hc::MeasuredResponse& m : r.responses) {
    list.push_back({{"label", m.label},
                    {"operating_point_v", m.operating_point},
                    {"amplitude_v", m.amplitude},
                    {"low_frequency_gain", hc::low_frequency_gain(m)},
                    {"lowest_coherence", *std::min_element(m.coherence.begin(), m.coherence.end())},
                    {"output_noise_rms", m.output_noise_rms},
                    {"lines", m.size()},
                    {"band_hz", {m.frequency_hz.front(), m.frequency_hz.back()}}});
  }
  const std::vector<hc::MeasuredMode> modes = hc::measured_modes(r.responses);
  json mode_list = json::array();
  for (const hc::MeasuredMode& m : modes) {
    mode_list.push_back({{"frequency_hz", m.frequency_hz},
                         {"damping_ratio", m.damping_ratio},
                         {"peak_db", m.peak_db}});
  }
  json out = {{"run_id", r.run_id}, {"responses", list}, {"modes", mode_list}};
  if (r.excitation.contains("left_out")) out["left_out"] = r.excitation["left_out"];
  if (r.moving) out["moving"] = hc::to_json(*r.moving);
  if (before != nullptr && !before->responses.empty()) {
    auto mean_gain = [](const hc::StageResponses& s) {
      double g = 0.0;
      for (const auto& m : s.responses) g += hc::low_frequency_gain(m);
      return g / static_cast<double>(s.responses.size());
    };
    json change = {{"since", before->run_id}, {"gain_ratio", mean_gain(r) / mean_gain(*before)}};
    const std::vector<hc::MeasuredMode> then = hc::measured_modes(before->responses);
    if (!modes.empty() && !then.empty()) {
      change["mode_hz"] = {then.front().frequency_hz, modes.front().frequency_hz};
    }
    out["change"] = change;
  }
  return out;
}

}  // namespace hystbench::daemon::details
