#include "runs/details/track_program.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/model_file_io.hpp"
#include "hystbench/compensation/compensator.hpp"
#include "hystbench/compensation/drive_planner.hpp"
#include "hystbench/compensation/dynamics_inversion.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/planned_inverse.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "hystbench/daemon/runs/track_drive.hpp"
#include "runs/details/learned_drive.hpp"
#include "runs/details/track_feedforward_plan.hpp"
#include "runs/details/track_reference.hpp"

namespace hystbench::daemon::details {

namespace hc = compensation;
using nlohmann::json;

namespace {

// A drive learned before plays at least this long ahead of its first scored period: a fast
// sine's single period leaves the actuator settling from rest (its fast creep, its modes) where
// the drive was learned on a periodic state, and the offset measured on the last of them is
// that of a settled motion (measurements.md, "the script's drives on the same bench").
constexpr double kLeadInS = 0.2;
// ... and at least this many periods: the first starts from rest, so the offset is measured on a
// whole period after it.
constexpr std::size_t kLeadInPeriods = 2;
// Where the actuator's offset is not the one the drive was learned at, the lead-in goes on while
// the offset moves toward it (creep), following it every kFollowS, until it is within
// kLeadInTolerance x the last trial's rms (the move the drive makes through the model to meet
// the rest has the model's shape, off the actuator's by a fraction of the move), or it came
// no closer by that over kStallS. Within it, the lead-in follows on until a step's mean error is
// within kLeadInSettled x the last trial's rms (the actuator answers the move of the target by
// the model's gain there, not exactly by the move: the step after a move shows the rest), for
// at most LearningLeadIn::settle_steps steps.
constexpr double kFollowS = 0.1;
constexpr double kLeadInTolerance = 5.0;
constexpr double kLeadInSettled = 1.0;
constexpr double kStallS = 5.0;

ActuatorRange known_range(const RunContext& ctx) {
  if (const auto range = actuator_range(ctx)) return *range;
  throw common::CommandError("no_range",
                             "the actuator range is unknown: identify or load a model, or set "
                             "limits.y_min and limits.y_max");
}

// A learning run's trials (track --learn): each one period of a periodic reference, P whole
// ticks (the frequency moves to the loop rate / P so that every trial samples the same points),
// or one pass of a user's trajectory (its approach from the end, then itself).
struct LearningPlan {
  std::size_t trials = 0;
  double gain = 0.5;
  double cutoff_hz = 0.0;             ///< Q's cut-off; 0 = IterativeLearning's default
  std::size_t period = 0;             ///< P [ticks]
  double frequency_hz = 0.0;          ///< the loop rate / P
  std::string reference;              ///< sine, triangle, sawtooth, or upload
  std::size_t scored_from = 0;        ///< a trial's first scored phase (an upload's approach: not)
  std::optional<LearnedDrive> start;  ///< the drive trial 0 plays (`learned`), else none
  /// The periods a drive learned before plays ahead of trial 0, unscored (a sine's, at least
  /// kLeadInS long; an upload's pass, one), and at most (LearningKeys::lead_in_max_s).
  std::size_t lead_in = 1;
  std::size_t lead_in_max = 1;
  double lead_in_max_s = 0.0;  ///< LearningKeys::lead_in_max_s (an upload's passes: reference())
};

// The plan of a learning run from its request; for an upload, reference() sets its period (a
// pass) and its scored part from the trajectory.
std::optional<LearningPlan> learning_plan(const TrackRequest& request, const RunContext& ctx) {
  const LearningKeys& keys = request.learning;
  if (!keys.any()) return std::nullopt;
  LearningPlan plan;
  plan.trials = keys.trials;
  plan.gain = keys.gain;
  plan.cutoff_hz = keys.cutoff_hz;
  if (keys.learned) plan.start = load_learned_drive(ctx.settings.model_dir, *keys.learned);
  plan.lead_in_max_s = keys.lead_in_max_s;
  if (!request.reference_upload.empty()) {
    plan.reference = "upload";
    return plan;
  }
  plan.reference = request.reference.name;
  const double rate = ctx.settings.loop.rate_hz;
  plan.period = static_cast<std::size_t>(std::llround(rate / request.reference.frequency_hz));
  plan.frequency_hz = rate / static_cast<double>(plan.period);
  if (plan.start) {
    plan.lead_in = std::max(kLeadInPeriods, periods_filling(kLeadInS, plan.frequency_hz));
    plan.lead_in_max =
        std::max(plan.lead_in, periods_filling(keys.lead_in_max_s, plan.frequency_hz));
  } else {
    // The start from rest rings the stage's modes: trial 0 and its repeat (the bench's floor)
    // wait until they have died out.
    plan.lead_in = plan.lead_in_max = periods_filling(ringing_time_s(ctx), plan.frequency_hz);
  }
  return plan;
}

TrackReference reference(const TrackRequest& request, const RunContext& ctx,
                         const ActuatorRange& range, const Upload* upload,
                         std::optional<LearningPlan>& learn) {
  const auto& lim = ctx.settings.loop.limits;
  const double span = range.y_top - range.y_bottom;
  const ReferenceLimits limits{range.y_bottom, range.y_top,
                               lim.slew_v_per_s * span / (lim.u_max - lim.u_min),
                               ctx.settings.loop.rate_hz};
  if (upload == nullptr) {
    if (!learn) return builtin_reference(request.reference, limits);
    // A drive learned before plays its lead-in periods unscored, the first the start from rest.
    const auto extra = static_cast<double>(learn->lead_in_max - 1);
    TrackReference ref =
        builtin_reference(request.reference, limits, learn->frequency_hz,
                          learning_periods(learn->trials, learn->frequency_hz) + extra);
    ref.unscored = learn->lead_in_max * learn->period;
    return ref;
  }
  // The precondition sweep leaves the output at the bottom of its range.
  const double approach_s = request.approach_s;
  if (!learn) return uploaded_reference(*upload, limits, range.y_bottom, approach_s);
  TrackReference ref = uploaded_reference(*upload, limits, range.y_bottom, approach_s,
                                          learn->trials, learn->start ? learn->lead_in_max_s : 0.0);
  learn->period = ref.pass_samples;
  learn->frequency_hz = ref.frequency_hz;
  learn->scored_from = ref.pass_approach;
  learn->lead_in_max = ref.lead_in_passes;
  return ref;
}

// The model's inverse, started in the state the actuator's history and then the sweep `prefix`
// leave it in; null for a compensator without one.
std::unique_ptr<hc::InverseModel> feedforward_inverse(hc::CompensatorKind kind,
                                                      const RunContext& ctx,
                                                      const std::vector<double>& prefix) {
  if (ctx.model == nullptr || !hc::needs_model(kind)) return nullptr;
  const hc::ActuatorModel m = model_at_start(ctx, prefix);
  try {
    return hc::make_inverse(m, kind == hc::CompensatorKind::kInverseMultiplicative
                                   ? hc::InverseKind::kMultiplicative
                                   : hc::InverseKind::kAuto);
  } catch (const hc::NotInvertibleError& e) {
    throw common::CommandError("not_invertible", e.what());
  } catch (const std::exception& e) {
    throw common::CommandError("bad_model", e.what());
  }
}

// The feedback (designed on the stage's measured responses, or the gains given by hand checked
// on them: feedback_design.hpp); `summary` states it. nullopt for a compensator without one.
// A periodic reference's fundamental_hz (0: none, or a run whose learning takes the repeated
// error) adds resonators at its harmonics to a designed loop.
std::optional<hc::FeedbackController> feedback_controller(const FeedbackGainsRequest& request,
                                                          hc::CompensatorKind kind,
                                                          const RunContext& ctx,
                                                          double fundamental_hz, json& summary,
                                                          std::optional<FeedbackPlan>& plan) {
  if (!hc::uses_feedback(kind)) return std::nullopt;
  plan = plan_feedback(ctx, kind, request);
  summary = plan->summary;
  try {
    return hc::FeedbackController(with_reference_harmonics(ctx, *plan, fundamental_hz, summary),
                                  ctx.dt());
  } catch (const std::exception& e) {
    throw common::CommandError("bad_params", e.what());
  }
}

// The feedforward inverts the whole model: hysteresis, creep and rate in the static inverse,
// the delay and dynamics from the previewed reference. Sets the preview and the tare; returns
// the summary.
json arm_feedforward(RunProgram& p, TrackDrive& track, const RunContext& ctx) {
  const hc::ActuatorModel& model = ctx.model->model;
  const hc::DynamicsInversion inversion(model, ctx.dt(), ctx.settings.feedforward_bandwidth_hz);
  json inverted = json::array({"hysteresis"});
  if (model.creep()) inverted.push_back("creep");
  const bool thresholds_law = model.hysteresis().thresholds_law().has_value();
  if (model.hysteresis().kind() == hc::ModelKind::kRateDependentPi || thresholds_law) {
    inverted.push_back("rate");
  }
  if (model.delay_samples() > 0 || model.delay_s() > 0.0) inverted.push_back("delay");
  if (model.dynamics()) inverted.push_back("dynamics");
  if (inversion.active()) track.program.preview = inversion;
  arm_tare(track, p.excitation.size(), model_exchange_ticks(ctx));
  json out = {{"inverted", inverted},
              {"preview_samples", inversion.preview_samples()},
              {"bandwidth_hz", inversion.bandwidth_hz()},
              {"how", inversion.describe()}};
  const auto* rpi = dynamic_cast<const hc::RateDependentPiModel*>(&model.hysteresis());
  if (thresholds_law) {
    out["rate"] =
        "solved each tick (thresholds widening with the rate): at the drive's own rate, exact, "
        "where the output still grows with the drive; else at the rate the rate-free inverse's "
        "drive predicts";
  } else if (rpi != nullptr) {
    out["rate"] = hc::can_plan_drive(model)
                      ? "planned over the known reference where it is fast (the |du/dt| law, or "
                        "weights that fall with the rate)"
                      : "solved each tick at the drive's own rate (the signed law, weights growing "
                        "with it: exact)";
  }
  return out;
}

// The mode the active model's identify timed on its record's steps, where it kept none in the
// model (the extension not adopted): a fast trial's learning meets it above Q.
std::optional<hc::DynamicsParameters> timed_mode(const RunContext& ctx) {
  if (ctx.model == nullptr) return std::nullopt;
  const nlohmann::json& id = ctx.model->identification;
  const nlohmann::json timing =
      id.value("extension", nlohmann::json::object()).value("timing", nlohmann::json::object());
  const double hz = timing.value("natural_frequency_hz", 0.0);
  const double zeta = timing.value("damping_ratio", 0.0);
  if (!(std::isfinite(hz) && hz > 0.0 && std::isfinite(zeta) && zeta > 0.0)) return std::nullopt;
  hc::DynamicsParameters mode;
  mode.natural_frequency_hz = hz;
  mode.damping_ratio = zeta;
  return mode;
}

// The learner of a learning run: the trials' exchange from the first scored period on, the
// active model (else the linear map of the limits) as its L, the drive limits of the loop.
std::unique_ptr<TrackLearning> learning(RunProgram& p, TrackDrive& track, const LearningPlan& plan,
                                        const RunContext& ctx, const TrackReference& ref,
                                        const FeedbackPlan* feedback) {
  const auto& lim = ctx.settings.loop.limits;
  const std::optional<hc::ActuatorModel> model = predictor(ctx, ctx.u_now);
  if (!model)
    throw common::CommandError("no_range", "learning needs a model or limits.y_min/y_max");
  track.learning =
      std::make_unique<LearningExchange>(plan.period, p.metrics_from, plan.lead_in_max);
  track.learning->follow_offset(plan.lead_in, {});
  hc::LearningOptions o;
  o.dt = ctx.dt();
  o.u_min = lim.u_min;
  o.u_max = lim.u_max;
  o.cutoff_hz = plan.cutoff_hz;
  o.fundamental_hz = ref.content_hz;
  o.bench_mode = timed_mode(ctx);
  o.measured_plant = learning_plant(ctx, feedback);
  if (lim.slew_v_per_s > 0.0) o.max_step = lim.slew_v_per_s * o.dt;
  LearningRequest r;
  r.trials = plan.trials;
  r.gain = plan.gain;
  r.range_um = ref.max_um - ref.min_um;
  r.frequency_hz = plan.frequency_hz;
  r.reference = plan.reference;
  r.rate_hz = ctx.settings.loop.rate_hz;
  r.min_um = ref.min_um;
  r.max_um = ref.max_um;
  r.signature = ref.signature;
  r.scored_from = plan.scored_from;
  if (plan.start) {
    check_learned_drive(*plan.start, learned_for(r, plan.period));
    r.start_drive = plan.start->u;
    r.start_compensator = plan.start->compensator;
    r.start_name = plan.start->name;
  }
  try {
    return std::make_unique<TrackLearning>(*model, *track.learning, r, o);
  } catch (const std::invalid_argument& e) {
    throw common::CommandError("bad_params", std::string("learning: ") + e.what());
  }
}

// The mean output `model` predicts over the tare's window of the run's precondition sweep
// (relaxed at the sweep's first drive, as the loop's predictor is); nullopt without a window.
std::optional<double> tare_window_prediction(hc::ActuatorModel model, const RunProgram& p,
                                             double dt) {
  const std::vector<double>& sweep = p.excitation;
  const TareWindow& tare = track_drive(p)->program.tare;
  if (sweep.empty() || tare.from >= sweep.size()) return std::nullopt;
  model.configure(dt);
  model.reset(sweep.front());
  double sum = 0.0;
  for (std::size_t k = 0; k < sweep.size(); ++k) {
    const double y = model.step(sweep[k]);
    if (k >= tare.from) sum += y;
  }
  return sum / static_cast<double>(sweep.size() - tare.from);
}

// The target offset a drive learned before is moved from, in the active model's terms. The
// drive moves by how far the compensator's feedforward moves from the one it was learned
// beside; saved, that one is the model's of then, and after the model changed (a second
// identify, another model loaded) the difference would hold the models' difference too, which
// the drive has already learned away. So the active compensator plays the reference ahead at
// the offset the drive was learned with (preparation below), and as the tare is the actuator's
// output less a model's prediction on the precondition sweep, that offset is moved by how far
// the two models' predictions there differ. nullopt: the drive moves as saved (saved without its
// offset, or no compensator to play ahead).
std::optional<double> learned_start_offset(const LearnedDrive& start, const RunProgram& p,
                                           const RunContext& ctx) {
  const double offset = start.meta.value("compensator_offset_um", std::nan(""));
  if (start.compensator.empty() || !std::isfinite(offset) || !track_drive(p)->program.compensator) {
    return std::nullopt;
  }
  const json then_model = start.meta.value("model", json());
  if (ctx.model == nullptr || !then_model.is_string()) return offset;
  const std::string name = then_model.get<std::string>();
  if (name.empty() || name.find('/') != std::string::npos) return offset;
  try {
    const hc::ModelFile then =
        common::load_model_file((std::filesystem::path(ctx.settings.model_dir) / name).string());
    const auto before = tare_window_prediction(then.model, p, ctx.dt());
    const auto now = tare_window_prediction(ctx.model->model, p, ctx.dt());
    if (before && now) return offset + (*before - *now);
  } catch (const std::exception&) {
    // The model of then is gone or unreadable: the offset stays in its terms.
  }
  return offset;
}

// After the feedforward's own preparation: the compensator's twin, which plays the reference at
// the learned drive's offset (learned_start_offset) beside it, tick by tick
// (TrackDrive::learned_twin): the drive moves from it.
RunPreparation with_learned_start(RunPreparation preparation, double offset) {
  if (preparation.stage.empty()) preparation.stage = "copying the compensator";
  preparation.work = [before = std::move(preparation.work), offset](
                         RunProgram& p, const std::function<void(double)>& progress) {
    if (before) before(p, progress);
    TrackDrive& track = *track_drive(p);
    TrackProgram& program = track.program;
    if (program.compensator && track.learning) {
      // Its state the compensator's at the run's start.
      program.learned_twin.emplace(*program.compensator);
      program.learned_twin_offset_um = offset;
    }
  };
  return preparation;
}

// How the lead-in of `start`, learned at `offset`, follows the actuator's offset beyond its
// minimum (none when the drive's last trial is not known).
LearningLeadIn lead_in_following(const LearnedDrive& start, const LearningPlan& plan, double offset,
                                 double rate_hz) {
  LearningLeadIn l;
  const json last = start.meta.value("last_trial", json());
  const double rms = last.is_object() ? last.value("rms_error_um", 0.0) : 0.0;
  if (!(rms > 0.0) || plan.lead_in_max <= plan.lead_in) return l;
  const double period_s = static_cast<double>(plan.period) / rate_hz;
  l.learned_offset = offset;
  l.tolerance = kLeadInTolerance * rms;
  l.settled = kLeadInSettled * rms;
  l.follow_periods = static_cast<std::size_t>(std::max(1.0, std::ceil(kFollowS / period_s)));
  l.stall_steps = static_cast<std::size_t>(
      std::max(1.0, std::ceil(kStallS / (static_cast<double>(l.follow_periods) * period_s))));
  return l;
}

// A learning run's learner; a drive learned before moves from the active compensator's
// feedforward at its offset, played ahead after the run's `preparation`.
std::unique_ptr<TrackLearning> arm_learning(RunProgram& p, TrackDrive& track,
                                            const LearningPlan& plan, const RunContext& ctx,
                                            const TrackReference& ref, RunPreparation& preparation,
                                            const FeedbackPlan* feedback) {
  std::unique_ptr<TrackLearning> learner = learning(p, track, plan, ctx, ref, feedback);
  if (plan.start) {
    if (const auto offset = learned_start_offset(*plan.start, p, ctx)) {
      preparation = with_learned_start(std::move(preparation), *offset);
      track.learning->follow_offset(
          plan.lead_in, lead_in_following(*plan.start, plan, *offset, ctx.settings.loop.rate_hz));
    }
  }
  return learner;
}

// A learning run's plan, for the run's header and the start reply.
json learning_summary(const LearningPlan& learn) {
  json l = {{"trials", learn.trials},
            {"gain", learn.gain},
            {"frequency_hz", learn.frequency_hz},
            {"period_samples", learn.period}};
  if (learn.scored_from > 0) l["scored_from"] = learn.scored_from;
  if (learn.start) {
    l["started_from"] = learn.start->name;
    l["lead_in_periods"] = learn.lead_in;
    if (learn.lead_in_max > learn.lead_in) l["lead_in_max_periods"] = learn.lead_in_max;
  }
  return l;
}

// A periodic reference (one unscored period, metrics_from = prefix + period) leaves a second
// period unscored, on which the feedforward re-tares: its mean error moves the target from the
// first scored tick on (TareMeasure::startup_um). The first period is the start from rest, whose
// mean is not the periodic motion's. Only beside the prefix's tare (a feedforward that inverts
// the model) and with two scored periods left; not for a learning run (it has its own lead-in)
// or an upload (its approach is not the trajectory). A run with feedback leaves the period
// unscored too, so that the feedforward alone and with its loop score the same periods, but
// keeps its target (the loop holds the mean from the reference's start, and the target's step
// would only kick the stage). Call with total_samples and metrics_from set.
void arm_periodic_startup(RunProgram& p, TareWindow& tare, const TrackReference& ref, bool learning,
                          bool feedback) {
  const std::uint64_t prefix = p.excitation.size(), period = ref.unscored;
  if (ref.frequency_hz <= 0.0 || learning || ref.pass_samples != 0 || period < 4 ||
      tare.from >= prefix || p.metrics_from != prefix + period ||
      p.total_samples < p.metrics_from + 3 * period) {
    return;
  }
  if (!feedback) tare.startup_from = p.metrics_from;
  p.metrics_from += period;
  if (!feedback) tare.startup_to = p.metrics_from;
}

// The run log's header and the start reply of a track run built as `p`.
void describe_track_run(BuiltRun& run, const RunProgram& p, const TrackReference& ref,
                        const RunContext& ctx, const std::string& comp_name, const json& feedback,
                        const std::optional<LearningPlan>& learn) {
  const BenchSettings& s = ctx.settings;
  json run_header = {{"kind", "track"}};
  run_header.update(ref.header);
  run_header.update({{"compensator", comp_name},
                     {"precondition_samples", p.excitation.size()},
                     {"metrics_from", p.metrics_from},
                     {"rate_hz", s.loop.rate_hz},
                     {"feedback", feedback}});
  run.header = {{"run", run_header},
                {"driver", s.driver_type},
                {"y_model", predictor_name(ctx)},
                {"model", model_header(ctx)}};
  run.reply = {{"reference", ref.reply},
               {"compensator", comp_name},
               {"feedback", feedback},
               {"feedforward", p.summary.value("feedforward", json(nullptr))}};
  if (learn) {
    const json l = learning_summary(*learn);
    run.header["run"]["learning"] = l;
    run.reply["learning"] = l;
  }
}

// A periodic reference where the loop amplifies (|S| > 1 at its fundamental, above the
// crossover) and no resonator of `pid` sits at it: the feedback adds to what the feedforward
// leaves there; `feedback` says so.
void note_feedback_at_reference(const std::optional<FeedbackPlan>& plan,
                                const std::optional<hc::FeedbackController>& pid,
                                const TrackReference& ref, double rate_hz, json& feedback) {
  if (!plan || !pid || !feedback.is_object() || ref.frequency_hz <= 0.0) return;
  const std::vector<hc::HarmonicResonator>& resonators = pid->law().harmonics.resonators;
  if (std::any_of(resonators.begin(), resonators.end(), [&](const hc::HarmonicResonator& r) {
        return std::abs(r.frequency_hz - ref.frequency_hz) <= 1e-9 * ref.frequency_hz;
      })) {
    return;
  }
  const double s_ref = sensitivity_at(*plan, ref.frequency_hz, 1.0 / rate_hz);
  if (std::isfinite(s_ref) && s_ref > 1.0) {
    feedback["at_reference"] = {
        {"frequency_hz", ref.frequency_hz},
        {"sensitivity", s_ref},
        {"note",
         "the reference's fundamental lies where the loop amplifies what the "
         "feedforward leaves (|S| above 1, above its crossover): the feedback can track "
         "it worse than the feedforward alone; --learn learns the repeated error"}};
  }
}

// make_track_program's and make_axis_track_program's run: `ref` built from the request,
// `feedforward_reference` the feedforward's in its place (null: the reference); `single_axis`
// false for one axis of a stage's run.
BuiltRun build_track_run(const TrackRequest& request, const RunContext& ctx, TrackReference ref,
                         std::optional<LearningPlan> learn,
                         std::unique_ptr<sim::SignalGenerator> feedforward_reference,
                         bool single_axis) {
  const BenchSettings& s = ctx.settings;
  const auto& lim = s.loop.limits;
  const std::string& comp_name = request.compensator;
  const hc::CompensatorKind kind = request.compensator_kind;
  const ActuatorRange range = known_range(ctx);

  auto p = std::make_unique<RunProgram>();
  p->kind = RunKind::kTrack;
  p->response_delay_ticks = model_delay_ticks(ctx);
  TrackDrive& track = make_track_drive(*p);
  track.program.reference = std::move(ref.signal);
  track.program.feedforward_reference = std::move(feedforward_reference);
  track.program.y_ref_min = range.y_bottom;
  track.program.y_ref_max = range.y_top;
  // Pre-conditioning: current output -> u_max -> u_min, open loop.
  p->excitation =
      precondition_sweep(ctx.u_now, lim.u_min, lim.u_max, request.precondition_s, ctx.dt());
  const double gain = (range.y_top - range.y_bottom) / (lim.u_max - lim.u_min);
  const hc::LinearMap linear{gain, range.y_bottom - gain * lim.u_min};
  json feedforward = nullptr;
  if (ctx.model != nullptr && hc::needs_model(kind)) feedforward = arm_feedforward(*p, track, ctx);
  std::unique_ptr<hc::InverseModel> inverse = feedforward_inverse(kind, ctx, p->excitation);
  json feedback = nullptr;
  std::optional<FeedbackPlan> plan;
  // One axis's periodic run without learning: the stage's axes share their modes, and a
  // learning run learns the repeated error itself.
  const bool harmonics = single_axis && !learn && !request.learning.learned;
  const std::optional<hc::FeedbackController> pid = feedback_controller(
      request.gains, kind, ctx, harmonics ? ref.frequency_hz : 0.0, feedback, plan);
  const hc::FeedbackPath path = plan ? plan->path : hc::FeedbackPath::kInverse;
  note_feedback_at_reference(plan, pid, ref, s.loop.rate_hz, feedback);
  RunPreparation preparation;
  if (inverse) {
    preparation = feedforward_plan(*p, ctx, kind, ref.samples, ref.frequency_hz, feedforward, pid,
                                   linear, path);
  }
  try {
    track.program.compensator.emplace(kind, std::move(inverse), pid, linear, path);
  } catch (const std::exception& e) {
    throw common::CommandError("bad_params", e.what());
  }
  p->model = predictor(ctx, p->excitation.empty() ? ctx.u_now : p->excitation.front());
  p->summary = {{"compensator", comp_name}};
  describe_predictor(ctx, p->summary);
  if (!feedforward.is_null()) p->summary["feedforward"] = feedforward;
  if (!feedback.is_null()) p->summary["feedback"] = feedback;

  const std::uint64_t prefix = p->excitation.size();
  p->total_samples = prefix + ref.samples;
  p->metrics_from = prefix + ref.unscored;
  arm_periodic_startup(*p, track.program.tare, ref, learn.has_value(), pid.has_value());
  // The feedback holds the reading to the reference from the reference's first tick on, so that
  // it has taken out the start from rest before the scored part begins (held until then, the
  // scored part began with the feedforward's error there).
  if (pid) p->feedback_from = prefix;
  // Its resonators take out the periodic error: the start from rest does not repeat.
  if (pid && !pid->law().harmonics.empty() && ref.unscored > 0) {
    track.program.harmonics_from = prefix + ref.unscored;
  }
  if (pid && s.pid.oscillation_trip) {
    OscillationOptions o = oscillation_options(feedback, ref.max_um - ref.min_um, s.loop.rate_hz);
    // A periodic reference: the supervisor watches the error's change over its period (what a
    // stable loop answers it with repeats; a fast one near the peak of |S| is large there).
    if (ref.frequency_hz > 0.0) o.period_samples = s.loop.rate_hz / ref.frequency_hz;
    p->oscillation.emplace(o);
  }
  allocate_records(*p);

  BuiltRun run;
  if (learn) {
    run.learning = arm_learning(*p, track, *learn, ctx, ref, preparation, plan ? &*plan : nullptr);
  }
  describe_track_run(run, *p, ref, ctx, comp_name, feedback, learn);
  if (plan) run.feedback_plan = std::make_shared<const FeedbackPlan>(std::move(*plan));
  run.status = {{"compensator", comp_name}};
  run.program = std::move(p);
  run.preparation = std::move(preparation);
  return run;
}

}  // namespace

TrackReference track_reference(const TrackRequest& request, const RunContext& ctx,
                               const Upload* reference_upload) {
  std::optional<LearningPlan> learn = learning_plan(request, ctx);
  return reference(request, ctx, known_range(ctx), reference_upload, learn);
}

BuiltRun make_track_program(const TrackRequest& request, const RunContext& ctx,
                            const Upload* upload) {
  std::optional<LearningPlan> learn = learning_plan(request, ctx);
  TrackReference ref = reference(request, ctx, known_range(ctx), upload, learn);
  return build_track_run(request, ctx, std::move(ref), std::move(learn), nullptr, true);
}

BuiltRun make_axis_track_program(const TrackRequest& request, const RunContext& ctx,
                                 const Upload* reference_upload, TrackReference axis_reference,
                                 std::unique_ptr<sim::SignalGenerator> feedforward_reference) {
  std::optional<LearningPlan> learn = learning_plan(request, ctx);
  // A learning run's plan takes its trials' period from the trajectory's passes.
  if (learn) (void)reference(request, ctx, known_range(ctx), reference_upload, learn);
  return build_track_run(request, ctx, std::move(axis_reference), std::move(learn),
                         std::move(feedforward_reference), false);
}

}  // namespace hystbench::daemon::details
