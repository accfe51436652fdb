#include "runs/details/feedback_design.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "hystbench/common/command_error.hpp"
#include "hystbench/compensation/feedback_plant.hpp"
#include "hystbench/compensation/harmonic_resonator_design.hpp"
#include "hystbench/compensation/number_text.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/sim/frequency_response_excitation.hpp"
#include "runs/details/response_program.hpp"
#include "runs/details/run_context.hpp"

namespace hystbench::daemon::details {

namespace hc = compensation;
using nlohmann::json;

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

// A figure for JSON: an infinite margin (no crossing in the band) as null.
json finite_or_null(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }

// The responses the bench designs on: the active model's, else its last measured; null if none.
const hc::StageResponses* stored_responses(const RunContext& ctx) {
  return ctx.model != nullptr && ctx.model->responses ? &*ctx.model->responses : ctx.responses;
}

// The modes the stored responses show (none without them).
std::vector<hc::MeasuredMode> stage_modes(const RunContext& ctx) {
  const hc::StageResponses* r = stored_responses(ctx);
  return r == nullptr ? std::vector<hc::MeasuredMode>{} : hc::measured_modes(r->responses);
}

const hc::StageResponses& measured_responses(const RunContext& ctx) {
  const hc::StageResponses* r = stored_responses(ctx);
  if (r == nullptr) {
    throw common::CommandError(
        "no_frequency_response",
        "the feedback is designed from the stage's measured frequency response, and none is "
        "stored for the active model or measured on this bench: run `hystbench frf` (seconds) "
        "or identify");
  }
  if (std::abs(r->rate_hz - ctx.settings.loop.rate_hz) > 1e-9 * r->rate_hz) {
    throw common::CommandError("stale_frequency_response",
                               "the frequency response was measured at a loop rate of " +
                                   hc::significant(r->rate_hz, 3) + " Hz and the loop runs at " +
                                   hc::significant(ctx.settings.loop.rate_hz, 3) +
                                   " Hz: run `hystbench frf`");
  }
  return *r;
}

double mean_slope(const RunContext& ctx) {
  const auto range = actuator_range(ctx);
  const auto& lim = ctx.settings.loop.limits;
  if (!range) {
    throw common::CommandError("no_range",
                               "the actuator range is unknown: identify or load a model, or set "
                               "limits.y_min and limits.y_max");
  }
  return (range->y_top - range->y_bottom) / (lim.u_max - lim.u_min);
}

// Beside a feedback, the learning takes the loop's sensitivity as at least this.
constexpr double kLearnedSensitivity = 0.1;

bool rate_dependent(const RunContext& ctx) {
  return ctx.model != nullptr &&
         ctx.model->model.hysteresis().kind() == hc::ModelKind::kRateDependentPi;
}

// Where the loop's correction enters the drive (compensator.hpp).
hc::FeedbackPath feedback_path(const RunContext& ctx, hc::CompensatorKind kind,
                               const FeedbackGainsRequest& gains) {
  return kind == hc::CompensatorKind::kPid || ctx.model == nullptr || rate_dependent(ctx) ||
                 gains.through_linear_map
             ? hc::FeedbackPath::kLinearMap
             : hc::FeedbackPath::kInverse;
}

// The part of a rate law's output change per unit input rate [µm per V/s] that lowers the output
// as the drive moves on: with |du/dt| every coefficient's step does on a falling branch, with the
// signed rate the ones that fall; times the largest input. A right-half-plane zero at g / K_r
// while the stage moves, which a measurement around a resting operating point does not show.
double lowering_rate_gain(const hc::ActuatorModel& model) {
  const auto& p = static_cast<const hc::RateDependentPiModel&>(model.hysteresis()).parameters();
  if (p.rate_law == hc::RateLaw::kThresholds) return 0.0;
  const double u_abs = std::max(std::abs(model.input_min), std::abs(model.input_max));
  const bool signed_rate = p.rate_law == hc::RateLaw::kSigned;
  double sum = 0.0, prev = 0.0;
  for (const double c : p.rate_coefficients) {
    sum += signed_rate ? std::max(prev - c, 0.0) : std::abs(c - prev);
    prev = c;
  }
  return sum * u_abs;
}

// The responses seen through the model's static part, or (kLinearMap) the linear map.
std::vector<hc::MeasuredResponse> seen_through(const RunContext& ctx, hc::FeedbackPath path,
                                               const hc::StageResponses& r, double gain) {
  if (path == hc::FeedbackPath::kLinearMap || ctx.model == nullptr) {
    return hc::responses_through_gain(r.responses, gain);
  }
  const sim::FrequencyResponseExcitation x =
      sim::make_frequency_response_excitation(response_options_from_json(r.excitation));
  try {
    return hc::responses_through_model(r.responses, r.segments, ctx.model->model, x.u, r.rate_hz);
  } catch (const std::invalid_argument& e) {
    throw common::CommandError("bad_model", std::string("the feedback's plant: ") + e.what());
  }
}

// Through the linear map, the loop sees the stage's own slope, steeper along its loop than a
// small signal at rest shows (feedback_plant.hpp): the response steepest along the loop, scaled
// by how much steeper the model's branch climbs, is one more plant the design must hold. None
// below 5 % or without a model.
constexpr double kMotionScaleFloor = 1.05;

std::optional<hc::MeasuredResponse> along_the_loop(const RunContext& ctx,
                                                   const hc::StageResponses& r, double gain) {
  if (ctx.model == nullptr) return std::nullopt;
  const sim::FrequencyResponseExcitation x =
      sim::make_frequency_response_excitation(response_options_from_json(r.excitation));
  hc::MotionScale m;
  try {
    m = hc::motion_scale(r.responses, r.segments, ctx.model->model, x.u, r.rate_hz);
  } catch (const std::invalid_argument& e) {
    throw common::CommandError("bad_model", std::string("the feedback's plant: ") + e.what());
  }
  if (m.ratio < kMotionScaleFloor) return std::nullopt;
  hc::MeasuredResponse moving = r.responses[m.response];
  for (auto& v : moving.response) v *= m.ratio / gain;
  for (auto& v : moving.noise) v *= m.ratio / gain;
  moving.label = r.responses[m.response].label + ", along the loop (x" +
                 hc::significant(m.ratio, 3) +
                 ": the model's steepest branch over its slope at rest)";
  return moving;
}

// The responses as the loop of `kind` sees them.
std::vector<hc::MeasuredResponse> plants(const RunContext& ctx, hc::FeedbackPath path,
                                         const hc::StageResponses& r, double gain) {
  std::vector<hc::MeasuredResponse> out = seen_through(ctx, path, r, gain);
  if (path == hc::FeedbackPath::kLinearMap) {
    if (auto moving = along_the_loop(ctx, r, gain)) out.push_back(std::move(*moving));
  }
  return out;
}

hc::LoopDesignOptions design_options(const RunContext& ctx, const hc::StageResponses& r,
                                     double gain) {
  const PidSection& c = ctx.settings.pid;
  hc::LoopDesignOptions o;
  o.dt_s = ctx.dt();
  o.targets = {c.gain_margin_db, c.phase_margin_deg, c.peak_sensitivity_db};
  o.output_limit = std::max(std::abs(c.u_fb_min), std::abs(c.u_fb_max)) * gain;
  if (c.bandwidth_hz) {
    o.max_crossover_hz = *c.bandwidth_hz;
    o.max_crossover_reason = "pid.bandwidth_hz";
  }
  if (r.moving) {
    // Measured while the stage moved: the zero a rate law puts there, if any.
    if (r.moving->zero_hz > 0.0) {
      o.rhp_zero_hz = r.moving->zero_hz;
      o.rhp_zero_reason = "the stage while it moves (its " + r.moving->lagging +
                          " ramps lag the others by " + hc::significant(r.moving->lag_deg, 3) +
                          " deg at " + hc::significant(r.moving->frequency_hz, 3) +
                          " Hz: a rate law)";
    }
  } else if (rate_dependent(ctx)) {
    // Responses from before the moving part was measured: the model's law stands for it.
    const double kr = lowering_rate_gain(ctx.model->model);
    if (kr > 0.0) {
      o.rhp_zero_hz = gain / kr / (2.0 * std::numbers::pi);
      o.rhp_zero_reason =
          "the model's rate law (its rate lowers the output while the stage moves; not measured "
          "moving: run frf)";
    }
  }
  return o;
}

json margins_json(const hc::LoopEvaluation& e, const std::vector<hc::MeasuredResponse>& plants) {
  json out = json::array();
  for (std::size_t i = 0; i < e.margins.size(); ++i) {
    const hc::LoopMargins& m = e.margins[i];
    out.push_back({{"response", plants[i].label},
                   {"stable", m.stable},
                   {"gain_margin_db", finite_or_null(m.gain_margin_db)},
                   {"gain_margin_hz", m.gain_margin_hz},
                   {"phase_margin_deg", finite_or_null(m.phase_margin_deg)},
                   {"crossover_hz", m.crossover_hz},
                   {"peak_sensitivity_db", m.peak_sensitivity_db},
                   {"peak_sensitivity_hz", m.peak_sensitivity_hz},
                   {"bandwidth_hz", m.bandwidth_hz},
                   {"rejection_bandwidth_hz", m.rejection_bandwidth_hz},
                   {"tenfold_rejection_hz", m.tenfold_rejection_hz}});
  }
  return out;
}

json law_json(const hc::FeedbackLaw& law) {
  json notches = json::array();
  for (const hc::Notch& n : law.shaping.notches) {
    notches.push_back(
        {{"frequency_hz", n.frequency_hz}, {"damping", n.damping}, {"depth", n.depth}});
  }
  json out = {{"kp", law.pid.kp},
              {"ki", law.pid.ki},
              {"kd", law.pid.kd},
              {"derivative_filter_hz", law.pid.derivative_filter_hz},
              {"output_filter_hz", law.pid.output_filter_hz},
              {"notches", notches},
              {"v_limit_um", law.pid.output_max}};
  // The boost and the low-pass are there only where the design has them.
  if (law.boost.frequency_hz > 0.0) {
    out["boost"] = {{"frequency_hz", law.boost.frequency_hz}, {"gain", law.boost.gain}};
  }
  const auto& lp = law.shaping.low_pass;
  if (lp.frequency_hz > 0.0) {
    out["low_pass"] = {{"frequency_hz", lp.frequency_hz}, {"damping", lp.damping}};
  }
  return out;
}

json summary_json(const FeedbackPlan& p, const hc::StageResponses& r,
                  const hc::LoopDesignOptions& o) {
  const hc::LoopEvaluation& e = p.evaluation;
  json s = {{"law", law_json(p.law)},
            {"units",
             "per um of error: kp [1], ki [1/s], kd [s]; the output corrects the "
             "feedforward's target [um]"},
            {"through",
             p.path == hc::FeedbackPath::kLinearMap ? "the linear map" : "the model's inverse"},
            {"responses_from", r.run_id},
            {"crossover_hz", e.crossover_hz},
            {"bandwidth_hz", e.bandwidth_hz},
            {"rejection_bandwidth_hz", e.rejection_bandwidth_hz},
            {"tenfold_rejection_hz", e.tenfold_rejection_hz},
            {"margins", margins_json(e, p.plants)},
            {"targets",
             {{"gain_margin_db", o.targets.gain_margin_db},
              {"phase_margin_deg", o.targets.phase_margin_deg},
              {"peak_sensitivity_db", o.targets.peak_sensitivity_db}}},
            {"meets_targets", e.meets_targets},
            {"robust",
             {{"stable", e.robust}, {"gain", o.gain_uncertainty}, {"mode", o.mode_uncertainty}}},
            {"drive_noise_rms_um", e.drive_noise_rms},
            {"output_noise_rms_um", e.output_noise_rms}};
  return s;
}

// Gains given by hand [V/µm ...] as the loop's law on the target [per µm], at the mean slope.
hc::FeedbackLaw hand_law(const PidSection& c, const FeedbackGainsRequest& g, double gain,
                         double v_limit) {
  hc::FeedbackLaw law;
  law.pid.kp = g.kp.value_or(c.kp.value_or(0.0)) * gain;
  law.pid.ki = g.ki.value_or(c.ki.value_or(0.0)) * gain;
  law.pid.kd = g.kd.value_or(c.kd.value_or(0.0)) * gain;
  law.pid.derivative_filter_hz = c.derivative_filter_hz;
  law.pid.output_filter_hz = c.output_filter_hz.value_or(0.0);
  law.pid.output_min = -v_limit;
  law.pid.output_max = v_limit;
  return law;
}

std::string refusal(const hc::LoopEvaluation& e, const std::vector<hc::MeasuredResponse>& plants,
                    const hc::LoopTargets& t) {
  std::string s = "these gains break the loop's targets (gain margin >= " +
                  hc::significant(t.gain_margin_db, 3) +
                  " dB, phase margin >= " + hc::significant(t.phase_margin_deg, 3) +
                  " deg, peak |S| <= " + hc::significant(t.peak_sensitivity_db, 3) +
                  " dB) on the measured responses: " + e.failure + ". Margins:";
  for (std::size_t i = 0; i < e.margins.size(); ++i) {
    const hc::LoopMargins& m = e.margins[i];
    s += " " + plants[i].label + ": " + (m.stable ? "stable" : "UNSTABLE") + ", gain margin " +
         (std::isfinite(m.gain_margin_db) ? hc::significant(m.gain_margin_db, 3) + " dB" : "none") +
         ", phase margin " +
         (std::isfinite(m.phase_margin_deg) ? hc::significant(m.phase_margin_deg, 3) + " deg"
                                            : "none") +
         ", peak |S| " + hc::significant(m.peak_sensitivity_db, 3) + " dB;";
  }
  return s + " `hystbench tune` prints the designed loop; force_gains runs them anyway";
}

bool gains_by_hand(const RunContext& ctx, const FeedbackGainsRequest& gains) {
  const PidSection& c = ctx.settings.pid;
  return gains.any() || c.kp || c.ki || c.kd;
}

// What a plan is kept under: the model, the compensator, the responses and the gains.
std::string plan_key(const RunContext& ctx, hc::CompensatorKind kind,
                     const FeedbackGainsRequest& gains, const hc::StageResponses& r) {
  const PidSection& c = ctx.settings.pid;
  auto number = [](const std::optional<double>& a, const std::optional<double>& b) {
    return a ? hc::significant(*a, 3) : b ? hc::significant(*b, 3) : "-";
  };
  return std::to_string(ctx.model_generation) + "/" + std::string(hc::to_string(kind)) + "/" +
         r.run_id + "/" +
         (gains_by_hand(ctx, gains) ? number(gains.kp, c.kp) + "," + number(gains.ki, c.ki) + "," +
                                          number(gains.kd, c.kd) + (gains.force ? "!" : "")
                                    : "designed") +
         (gains.through_linear_map ? "/linear" : "");
}

void keep_plan(const RunContext& ctx, const std::string& key, const FeedbackPlan& p) {
  if (!ctx.feedback_plans) return;
  std::lock_guard lock(ctx.feedback_plans->mutex);
  auto& plans = ctx.feedback_plans->plans;
  std::erase_if(plans, [&](const auto& kept) { return kept.first == key; });
  if (plans.size() >= FeedbackPlanCache::kPlans) plans.erase(plans.begin());
  plans.emplace_back(key, p);
}

}  // namespace

FeedbackPlan plan_feedback(const RunContext& ctx, hc::CompensatorKind kind,
                           const FeedbackGainsRequest& gains) {
  const hc::StageResponses& r = measured_responses(ctx);
  const PidSection& c = ctx.settings.pid;
  const double gain = mean_slope(ctx);
  const hc::LoopDesignOptions o = design_options(ctx, r, gain);
  const bool by_hand = gains_by_hand(ctx, gains);
  const std::string key = plan_key(ctx, kind, gains, r);
  if (ctx.feedback_plans) {
    std::lock_guard lock(ctx.feedback_plans->mutex);
    for (const auto& [k, plan] : ctx.feedback_plans->plans) {
      if (k == key) return plan;
    }
  }
  FeedbackPlan p;
  p.path = feedback_path(ctx, kind, gains);
  p.plants = plants(ctx, p.path, r, gain);
  if (by_hand) {
    p.law = hand_law(c, gains, gain, o.output_limit);
    p.evaluation = hc::check_loop(p.plants, p.law, o);
    if (!p.evaluation.ok() && !gains.force) {
      throw common::CommandError("unsafe_gains", refusal(p.evaluation, p.plants, o.targets));
    }
    p.summary = summary_json(p, r, o);
    p.summary["gains"] = gains.any() ? "request" : "config";
    p.summary["forced"] = !p.evaluation.ok();
    if (!p.evaluation.ok()) p.summary["broken"] = p.evaluation.failure;
  } else {
    const hc::LoopDesign d = hc::design_loop(p.plants, o);
    if (!d.found) throw common::CommandError("no_design", d.limit);
    p.law = d.law;
    p.evaluation = d.evaluation;
    p.summary = summary_json(p, r, o);
    p.summary["gains"] = "designed";
    p.summary["structure"] = d.structure;
    p.summary["limited_by"] = d.limited_by;
    p.summary["limit"] = d.limit;
    json modes = json::array();
    for (const hc::MeasuredMode& m : d.modes) {
      modes.push_back({{"frequency_hz", m.frequency_hz},
                       {"damping_ratio", m.damping_ratio},
                       {"peak_db", m.peak_db}});
    }
    p.summary["modes"] = modes;
  }
  if (gains.through_linear_map && kind != hc::CompensatorKind::kPid && ctx.model != nullptr &&
      !rate_dependent(ctx)) {
    p.summary["through_why"] =
        "a stage's learning run: through each axis's inverse the correction jumps where its "
        "target crosses the model's cells, at ticks that differ from trial to trial, and rings "
        "the mode the axes share; the learned drive takes the hysteresis";
  }
  keep_plan(ctx, key, p);
  return p;
}

hc::FeedbackLaw with_loop_gain(hc::FeedbackLaw law, double factor) {
  law.pid.kp *= factor;
  law.pid.ki *= factor;
  law.pid.kd *= factor;
  return law;
}

FeedbackPlan lowered_plan(const RunContext& ctx, hc::CompensatorKind kind,
                          const FeedbackGainsRequest& gains, const FeedbackPlan& plan,
                          double factor, const nlohmann::json& why) {
  const hc::StageResponses& r = measured_responses(ctx);
  const hc::LoopDesignOptions o = design_options(ctx, r, mean_slope(ctx));
  FeedbackPlan p = plan;
  p.law = with_loop_gain(plan.law, factor);
  p.evaluation = hc::check_loop(p.plants, p.law, o);
  p.summary.update(summary_json(p, r, o));
  p.summary["lowered"] = {{"by", factor}, {"why", why}};
  p.summary["limited_by"] = "coupling";
  p.summary["limit"] = "lowered x" + hc::significant(factor, 3) + " from its design alone: " +
                       why.value("meaning", std::string("the stage's coupling"));
  keep_plan(ctx, plan_key(ctx, kind, gains, r), p);
  return p;
}

hc::FeedbackLaw with_reference_harmonics(const RunContext& ctx, const FeedbackPlan& plan,
                                         double fundamental_hz, json& feedback) {
  if (plan.summary.value("gains", std::string()) != "designed" || !(fundamental_hz > 0.0)) {
    return plan.law;
  }
  hc::HarmonicResonatorOptions o;
  o.dt_s = ctx.dt();
  o.fundamental_hz = fundamental_hz;
  const hc::HarmonicResonatorDesign d =
      hc::design_harmonic_resonators(plan.plants, plan.law, stage_modes(ctx), o);
  json kept = json::array(), left_out = json::array();
  for (std::size_t i = 0, r = 0; i < d.harmonics.size(); ++i) {
    const hc::HarmonicChoice& h = d.harmonics[i];
    json one = {{"harmonic", h.harmonic},
                {"frequency_hz", h.frequency_hz},
                {"sensitivity", h.sensitivity},
                {"phase_spread_deg", h.phase_spread_deg}};
    if (h.kept) {
      const std::complex<double> c = d.spec.resonators[r++].gain;
      one["gain"] = std::abs(c);
      one["phase_deg"] = std::arg(c) * kDeg;
      one["settle_s"] = h.settle_periods / fundamental_hz;
      kept.push_back(std::move(one));
    } else {
      one["why"] = h.why;
      left_out.push_back(std::move(one));
    }
  }
  json& out = feedback["harmonics"];
  out = {{"fundamental_hz", fundamental_hz}, {"resonators", kept.size()}};
  // Only what there is: no empty list, no settling of none.
  if (!kept.empty()) {
    out["kept"] = std::move(kept);
    out["settle_s"] = d.settle_periods / fundamental_hz;
    out["between_harmonics"] = d.between;
  }
  if (!left_out.empty()) out["left_out"] = std::move(left_out);
  out["rule"] =
      "a resonator at each of the reference's first " + std::to_string(o.max_harmonics) +
      " harmonics below the stage's first mode (beyond harmonic " +
      std::to_string(o.min_harmonics) + ", where a tick of delay turns the phase by at most " +
      hc::significant(o.max_tick_phase_deg, 3) +
      " deg) where the loop alone leaves more than "
      "half (|S| > " +
      hc::significant(o.min_sensitivity, 3) + ") and its phase through the stage holds within " +
      hc::significant(o.max_phase_spread_deg, 3) + " deg over the responses, their gain -/+ " +
      hc::significant(100.0 * o.gain_uncertainty, 3) + " % and their modes moved -/+ " +
      hc::significant(100.0 * o.mode_uncertainty, 3) +
      " %: it takes that harmonic out; settling as fast as leaves the loop between the harmonics "
      "moved by at most " +
      hc::significant(o.max_between, 3) +
      " of 1 + L (between_harmonics), the highest left out first where they cannot";
  hc::FeedbackLaw law = plan.law;
  law.harmonics = d.spec;
  return law;
}

OscillationOptions oscillation_options(const json& feedback, double span_um, double rate_hz) {
  OscillationOptions o;
  o.rate_hz = rate_hz;
  o.span_um = span_um;
  o.noise_rms_um = feedback.value("output_noise_rms_um", 0.0);
  double peak = -1e300;
  for (const json& m : feedback.value("margins", json::array())) {
    if (m.value("peak_sensitivity_db", -1e300) > peak) {
      peak = m["peak_sensitivity_db"].get<double>();
      o.frequency_hz = m.value("peak_sensitivity_hz", o.frequency_hz);
    }
  }
  return o;
}

double first_mode_hz(const RunContext& ctx) {
  double lowest = 0.0;
  for (const hc::MeasuredMode& m : stage_modes(ctx)) {
    if (lowest == 0.0 || m.frequency_hz < lowest) lowest = m.frequency_hz;
  }
  return lowest;
}

double ringing_time_s(const RunContext& ctx) {
  double slowest = 0.0;
  for (const hc::MeasuredMode& m : stage_modes(ctx)) {
    slowest = std::max(slowest, 1.0 / (2.0 * std::numbers::pi * m.frequency_hz * m.damping_ratio));
  }
  return 5.0 * slowest;
}

std::optional<hc::MeasuredLearningPlant> learning_plant(const RunContext& ctx,
                                                        const FeedbackPlan* feedback) {
  const hc::StageResponses* r = stored_responses(ctx);
  if (r == nullptr || std::abs(r->rate_hz - ctx.settings.loop.rate_hz) > 1e-9 * r->rate_hz) {
    return std::nullopt;
  }
  const double gain = mean_slope(ctx);
  const std::vector<hc::MeasuredResponse> seen =
      seen_through(ctx, hc::FeedbackPath::kInverse, *r, gain);
  std::optional<hc::FeedbackController> c;
  if (feedback != nullptr) c.emplace(feedback->law, ctx.dt());
  hc::MeasuredLearningPlant p;
  p.frequency_hz = seen.front().frequency_hz;
  p.response.assign(p.frequency_hz.size(), 0.0);
  p.stage_gain.assign(p.frequency_hz.size(), 0.0);
  const auto count = static_cast<double>(seen.size());
  for (std::size_t i = 0; i < seen.size(); ++i) {
    if (seen[i].frequency_hz != p.frequency_hz) return std::nullopt;
    for (std::size_t j = 0; j < p.frequency_hz.size(); ++j) {
      std::complex<double> x = seen[i].response[j];
      p.stage_gain[j] += std::abs(x) / count;
      if (c) {
        // The loop's own plant (its path may be the linear map) sets its sensitivity, held at
        // kLearnedSensitivity at least: where the loop takes out more, the learning goes slower
        // (it would otherwise amplify each trial's noise there by 1 / |S| into the drive).
        const double f = p.frequency_hz[j];
        const std::complex<double> l = c->response(f) *
                                       std::polar(1.0, -2.0 * std::numbers::pi * f * ctx.dt()) *
                                       feedback->plants[i].response[j];
        std::complex<double> s = 1.0 / (1.0 + l);
        if (std::abs(s) < kLearnedSensitivity) s *= kLearnedSensitivity / std::abs(s);
        x *= s;
      }
      p.response[j] += x / count;
    }
  }
  return p;
}

json loop_curves(const FeedbackPlan& plan, double dt_s) {
  const hc::FeedbackController c(plan.law, dt_s);
  json out = json::array();
  for (std::size_t i = 0; i < plan.plants.size(); ++i) {
    const hc::MeasuredResponse& p = plan.plants[i];
    const std::vector<std::complex<double>> l = hc::loop_response(p, c, dt_s);
    std::vector<double> f = p.frequency_hz, mag, phase, s, t;
    f.push_back(0.5 / dt_s);
    for (const auto& x : l) {
      mag.push_back(std::abs(x));
      phase.push_back(std::arg(x) * kDeg);
      s.push_back(1.0 / std::abs(1.0 + x));
      t.push_back(std::abs(x / (1.0 + x)));
    }
    out.push_back({{"response", p.label},
                   {"frequency_hz", f},
                   {"loop_magnitude", mag},
                   {"loop_phase_deg", phase},
                   {"sensitivity", s},
                   {"complementary", t}});
  }
  return out;
}

double sensitivity_at(const FeedbackPlan& plan, double frequency_hz, double dt_s) {
  const hc::FeedbackController c(plan.law, dt_s);
  double largest = std::numeric_limits<double>::quiet_NaN();
  for (const hc::MeasuredResponse& p : plan.plants) {
    if (p.size() < 2 || frequency_hz < p.frequency_hz.front() ||
        frequency_hz > p.frequency_hz.back()) {
      continue;
    }
    const std::vector<std::complex<double>> l = hc::loop_response(p, c, dt_s);
    const auto above = std::upper_bound(p.frequency_hz.begin(), p.frequency_hz.end(), frequency_hz);
    const auto i = static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(
        above - p.frequency_hz.begin(), 1, static_cast<std::ptrdiff_t>(p.size()) - 1));
    const double f0 = p.frequency_hz[i - 1], f1 = p.frequency_hz[i];
    const double w = (frequency_hz - f0) / (f1 - f0);
    const double s = (1.0 - w) / std::abs(1.0 + l[i - 1]) + w / std::abs(1.0 + l[i]);
    if (!(s <= largest)) largest = s;
  }
  return largest;
}

}  // namespace hystbench::daemon::details
