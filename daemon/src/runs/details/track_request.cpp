#include "runs/details/track_request.hpp"

#include <string>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/run_requests.hpp"

namespace hystbench::daemon::details {

namespace hc = compensation;
using common::CommandError;

namespace {

void parse_compensator(const RequestParams& request, const RunContext& ctx, TrackRequest& r) {
  r.compensator = request.string("compensator", ctx.model ? "inverse" : "none");
  const auto kind = hc::compensator_kind_from_string(r.compensator);
  if (!kind) {
    throw CommandError("bad_params", "compensator: unknown '" + r.compensator +
                                         "' (none, inverse, inverse_multiplicative, "
                                         "inverse+pid, pid)");
  }
  if (hc::needs_model(*kind) && ctx.model == nullptr) {
    throw CommandError("no_model", "compensator '" + r.compensator +
                                       "' needs a model: run identify or model.load first");
  }
  r.compensator_kind = *kind;
}

// A learning run's keys. Its trials are periods of the reference (or passes of an upload), so
// the run's length is theirs and a built-in reference must repeat.
void parse_learning(const RequestParams& request, const RunContext& ctx, TrackRequest& r) {
  LearningKeys& l = r.learning;
  l.trials = static_cast<std::size_t>(request.integer("learn_trials"));
  if (l.trials == 0) {
    for (const char* key : {"learn_gain", "learn_cutoff_hz"}) {
      if (request.has(key)) {
        throw CommandError("bad_params", std::string(key) + ": only with learn_trials > 0");
      }
    }
  }
  l.gain = request.number("learn_gain");
  l.cutoff_hz = request.number("learn_cutoff_hz", 0.0, 1e-3, 0.45 * ctx.settings.loop.rate_hz);
  if (request.has("learned")) l.learned = request.string("learned", "");
  if (request.has("lead_in_max_s") && !l.learned) {
    throw CommandError("bad_params", "lead_in_max_s: only with learned");
  }
  l.lead_in_max_s = request.number("lead_in_max_s");
  if (!l.any() || !r.reference_upload.empty()) return;
  const std::string key = l.trials > 0 ? "learn_trials" : "learned";
  const std::string& name = r.reference.name;
  if (name != "sine" && name != "triangle" && name != "sawtooth") {
    throw CommandError("bad_params", key +
                                         ": a trial is one period of a sine, triangle or "
                                         "sawtooth, or one pass of an uploaded trajectory; '" +
                                         name + "' does not repeat");
  }
  if (request.has("periods") || request.has("duration_s")) {
    throw CommandError("bad_params", key +
                                         " sets the run's length (the start-up period, the "
                                         "first trial and the learned ones): leave out periods "
                                         "and duration_s");
  }
}

// A setpoint move's rise: three periods of the stage's first mode, so that the move does not ring
// it; at least four ticks.
double step_rise_s(const RunContext& ctx) {
  double mode_hz = first_mode_hz(ctx);
  if (mode_hz <= 0.0 && ctx.model != nullptr && ctx.model->model.dynamics()) {
    mode_hz = ctx.model->model.dynamics()->natural_frequency_hz;
  }
  const double ticks = 4.0 * ctx.dt();
  return mode_hz > 0.0 ? std::max(ticks, 3.0 / mode_hz) : ticks;
}

void parse_builtin_reference(const RequestParams& request, const RunContext& ctx,
                             BuiltinReferenceRequest& ref) {
  try {
    ref.kind = sim::signal_kind_from_string(ref.name);
  } catch (const std::exception& e) {
    throw CommandError("bad_params", std::string("reference: ") + e.what());
  }
  if (ref.kind == sim::SignalKind::kSteps || ref.kind == sim::SignalKind::kSamples) {
    throw CommandError("bad_params", "reference: '" + ref.name +
                                         "' needs data; use sine, triangle, sawtooth, step, "
                                         "decaying_sine, multi_frequency or chirp, or upload "
                                         "a trajectory (reference_upload)");
  }
  const double rate = ctx.settings.loop.rate_hz;
  ref.frequency_hz = request.number_within("frequency_hz", 1e-3, rate / 20.0);
  ref.periods = request.number("periods");
  ref.duration_s = request.number("duration_s", 0.0);
  // A step is a setpoint move: a fifth of the range by default (a triangle or sine spans 0.8).
  ref.range_fraction = ref.kind == sim::SignalKind::kStep ? request.number("range_fraction", 0.2)
                                                          : request.number("range_fraction");
  if (request.has("min_um")) ref.min_um = request.number("min_um", 0.0);
  if (request.has("max_um")) ref.max_um = request.number("max_um", 0.0);
  if (ref.kind == sim::SignalKind::kStep) ref.rise_s = step_rise_s(ctx);
}

}  // namespace

TrackRequest parse_track_request(const RequestParams& request, const RunContext& ctx) {
  TrackRequest r;
  // A stage's built-in reference plays as uploads: their approach is the default's.
  r.approach_s = default_number(common::request_fields::kApproach);
  parse_compensator(request, ctx, r);
  // track's two parameter rows: a built-in reference's keys, or an upload's (with approach_s).
  if (request.has("reference_upload")) {
    r.reference_upload = request.string("reference_upload", "");
    if (r.reference_upload.empty()) {
      throw CommandError("bad_params", "reference_upload: the name of a complete upload, not ''");
    }
    r.approach_s = request.number("approach_s");
  } else {
    r.reference.name = request.string("reference");
  }
  parse_learning(request, ctx, r);
  if (r.reference_upload.empty()) parse_builtin_reference(request, ctx, r.reference);
  r.precondition_s = request.number("precondition_s", ctx.settings.precondition_s);
  if (request.has("kp")) r.gains.kp = request.number("kp", 0.0);
  if (request.has("ki")) r.gains.ki = request.number("ki", 0.0);
  if (request.has("kd")) r.gains.kd = request.number("kd", 0.0);
  r.gains.force = request.boolean("force_gains", ctx.settings.pid.force);
  return r;
}

}  // namespace hystbench::daemon::details
