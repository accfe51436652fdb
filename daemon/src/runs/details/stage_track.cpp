// A stage's track and its result (stage_runs.hpp).
#include <algorithm>
#include <cmath>
#include <complex>
#include <initializer_list>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/run_requests.hpp"
#include "hystbench/compensation/dynamics_inversion.hpp"
#include "hystbench/compensation/loop_analysis.hpp"
#include "hystbench/compensation/number_text.hpp"
#include "hystbench/compensation/stage_coupling_error.hpp"
#include "hystbench/compensation/stage_dynamic_decoupling.hpp"
#include "hystbench/compensation/stage_interaction.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "hystbench/daemon/runs/track_drive.hpp"
#include "runs/details/feedback_design.hpp"
#include "runs/details/stage_loops_together.hpp"
#include "runs/details/stage_runs.hpp"
#include "runs/details/track_program.hpp"

namespace hystbench::daemon::details {

using common::CommandError;
using nlohmann::json;
namespace hc = hystbench::compensation;

namespace {

// What each built-in kind plays by default: raster 10 Hz lines over a 0.1 Hz frame, one frame;
// lissajous 10 and 11 Hz, two of their common periods; spiral ten turns a second, 10 s in.
sim::StageReferenceSpec builtin_defaults(sim::StageReferenceKind kind, std::size_t axes) {
  sim::StageReferenceSpec spec;
  spec.kind = kind;
  switch (kind) {
    case sim::StageReferenceKind::kRaster:
      spec.frequencies_hz = {10.0, 0.1};
      spec.duration_s = 10.0;
      break;
    case sim::StageReferenceKind::kLissajous:
      spec.frequencies_hz.clear();
      for (std::size_t a = 0; a < axes; ++a) spec.frequencies_hz.push_back(10.0 + a);
      spec.duration_s = 2.0;
      break;
    case sim::StageReferenceKind::kSpiral:
      spec.frequencies_hz = {10.0};
      spec.duration_s = 10.0;
      break;
  }
  return spec;
}

// The samples of each axis's part of a built-in stage reference, as a reference upload.
std::vector<Upload> builtin_uploads(const sim::StageReferenceSpec& spec,
                                    std::span<const sim::AxisRange> ranges, double rate_hz) {
  std::vector<sim::SignalSpec> signals;
  try {
    signals = sim::stage_reference(spec, ranges);
  } catch (const std::exception& e) {
    throw CommandError("bad_params", e.what());
  }
  // A raster's frame or a Lissajous's run: duration_s; a spiral also holds its middle a tenth.
  const double seconds =
      spec.kind == sim::StageReferenceKind::kSpiral ? 1.1 * spec.duration_s : spec.duration_s;
  std::vector<Upload> out;
  for (std::size_t a = 0; a < signals.size(); ++a) {
    Upload u;
    u.name = std::string(sim::to_string(spec.kind)) + "-axis-" + std::to_string(a);
    u.source = "built-in " + std::string(sim::to_string(spec.kind));
    u.rate_hz = rate_hz;
    u.values = sim::sample_signal(*sim::make_signal_generator(signals[a]), 1.0 / rate_hz, seconds);
    u.values.push_back(sim::make_signal_generator(signals[a])->value(seconds));
    u.samples = u.values.size();
    out.push_back(std::move(u));
  }
  return out;
}

// What axis a's feedforward commands for own targets s (compensation::DynamicStageDecoupler::
// StrokeOf): its model's dynamics inverted as the feedforward inverts them (the reference's
// derivatives over +-h, linear between samples); empty for a model without dynamics.
hc::DynamicStageDecoupler::StrokeOf stroke_of(const RunContext& ctx) {
  if (ctx.model == nullptr || !ctx.model->model.dynamics()) return {};
  const hc::DynamicsInversion inversion(ctx.model->model, ctx.dt(),
                                        ctx.settings.feedforward_bandwidth_hz);
  const double h = inversion.step_s() / ctx.dt();  // [samples]
  return [inversion, h](std::span<const double> own, std::span<double> stroke) {
    const auto last = static_cast<double>(own.size() - 1);
    const auto at = [&](double k) {
      k = std::clamp(k, 0.0, last);
      const auto i = static_cast<std::size_t>(std::floor(k));
      const double f = k - static_cast<double>(i);
      return i + 1 < own.size() ? (1.0 - f) * own[i] + f * own[i + 1] : own[i];
    };
    for (std::size_t k = 0; k < own.size(); ++k) {
      const auto t = static_cast<double>(k);
      stroke[k] = inversion.target(at(t - h), own[k], at(t + h));
    }
  };
}

// The coupling's paths as the stage's cross responses show them (nullopt where a path is flat
// or was not measured), and the result's account of them.
struct CouplingPaths {
  hc::DynamicStageDecoupler::PathShapes shapes;
  json described = json::array();
  bool measured = false;  ///< some path's cross responses were measured
};

CouplingPaths coupling_paths(const StageModel& stage, double dt) {
  const std::size_t n = stage.axes.size();
  CouplingPaths out;
  out.shapes.assign(n, std::vector<std::optional<hc::CouplingPathShape>>(n));
  for (std::size_t i = 0; i < n && i < stage.cross.size(); ++i) {
    for (std::size_t j = 0; j < n && j < stage.cross[i].size(); ++j) {
      if (i == j || stage.cross[i][j].responses.empty()) continue;
      out.measured = true;
      const hc::ModelFile& own = stage.models[i];
      std::span<const hc::MeasuredResponse> own_responses;
      if (own.responses) own_responses = own.responses->responses;
      std::optional<hc::DynamicsParameters> inverted;
      if (own.model.dynamics()) inverted = *own.model.dynamics();
      out.shapes[i][j] =
          hc::coupling_path(stage.cross[i][j].responses, own_responses, inverted, dt);
      if (!out.shapes[i][j]) continue;
      const hc::CouplingPathShape& p = *out.shapes[i][j];
      json modes = json::array();
      for (const auto& m : p.modes) {
        modes.push_back({{"frequency_hz", m.parameters.natural_frequency_hz},
                         {"damping_ratio", m.parameters.damping_ratio},
                         {"share", m.share}});
      }
      out.described.push_back({{"into", stage.axes[i]},
                               {"from", stage.axes[j]},
                               {"gain", stage.decoupler.gains()(static_cast<Eigen::Index>(i),
                                                                static_cast<Eigen::Index>(j))},
                               {"direct_share", p.direct},
                               {"modes", modes},
                               {"lag_samples", p.lag_samples},
                               {"slope", p.slope},
                               {"curvature", p.curvature},
                               {"over_own_response", !own_responses.empty()},
                               {"misfit", p.misfit}});
    }
  }
  return out;
}

// Where each axis's own displacement targets go against its stroke (its model's range): the
// coupling taken out can ask an axis for more than it has (a stage coupled strongly, a
// reference over most of each range), which its inverse cannot give. An object per axis
// beyond its stroke by more than kReachTolerance of it, with how far [µm]; empty when every
// axis stays within. (The approach from rest starts each axis at its stroke's floor, where the
// others' share taken out dips a few hundredths of a µm below it: within the tolerance.)
constexpr double kReachTolerance = 0.01;

json own_reach(const Eigen::MatrixXd& own, std::span<const std::string> axes,
               std::span<const sim::AxisRange> ranges) {
  json out = json::object();
  for (Eigen::Index a = 0; a < own.rows(); ++a) {
    const auto au = static_cast<std::size_t>(a);
    if (au >= ranges.size() || au >= axes.size()) break;
    const double below = ranges[au].min - own.row(a).minCoeff();
    const double above = own.row(a).maxCoeff() - ranges[au].max;
    if (std::max(below, above) <= kReachTolerance * (ranges[au].max - ranges[au].min)) continue;
    out[axes[au]] = {{"below_um", std::max(below, 0.0)},
                     {"above_um", std::max(above, 0.0)},
                     {"stroke_um", {ranges[au].min, ranges[au].max}},
                     {"meaning",
                      "the other axes' share taken out asks this axis for more than its stroke: "
                      "it cannot follow there; lower range_fraction or move the reference"}};
  }
  return out;
}

// The feedforward's targets with the coupling taken out: every axis's reference sampled over
// `samples` ticks (and its end held a second past them, for a preview ahead), decoupled with
// the paths' dynamics where the request asks for them and the stage's cross responses show
// them, else with the static gains; `how` says which (the result's decoupling.dynamic).
std::vector<std::unique_ptr<sim::SignalGenerator>> decoupled_targets(
    const std::vector<TrackReference>& refs, const StageModel& stage,
    const std::vector<RunContext>& contexts, std::span<const sim::AxisRange> ranges, bool dynamic,
    double dt, std::uint64_t samples, json& how) {
  const std::size_t n = refs.size();
  const std::uint64_t total = samples + static_cast<std::uint64_t>(std::llround(1.0 / dt));
  Eigen::MatrixXd r(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(total));
  for (std::uint64_t k = 0; k < total; ++k) {
    const double t = static_cast<double>(std::min(k, samples)) * dt;
    for (std::size_t a = 0; a < n; ++a) {
      r(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(k)) = refs[a].signal->value(t);
    }
  }
  std::optional<Eigen::MatrixXd> own;
  CouplingPaths paths = coupling_paths(stage, dt);
  how = {{"used", false}};
  if (!paths.measured) {
    how["why_not"] = "the stage's cross responses were not measured: identify again";
  } else if (paths.described.empty()) {
    how["why_not"] =
        "no coupling path shows a mode over its measured lines: the static gains are its "
        "coupling";
  } else if (!dynamic) {
    how["why_not"] = "decoupling = static (the default; dynamic takes these paths out too)";
    how["paths"] = paths.described;
  } else {
    std::vector<hc::DynamicStageDecoupler::StrokeOf> strokes;
    strokes.reserve(contexts.size());
    for (const RunContext& c : contexts) strokes.push_back(stroke_of(c));
    try {
      const hc::DynamicStageDecoupler decoupler(stage.decoupler.gains(), std::move(paths.shapes),
                                                dt);
      hc::DynamicStageDecoupler::Solution solved = decoupler.own_targets(r, strokes);
      how = {{"used", true}, {"paths", paths.described}, {"sweeps", solved.sweeps}};
      own = std::move(solved.own);
    } catch (const std::invalid_argument& e) {
      how["why_not"] = e.what();
      how["paths"] = paths.described;
    }
  }
  if (!own) {
    own.emplace(r.rows(), r.cols());
    std::vector<double> in(n), out(n);
    for (Eigen::Index k = 0; k < r.cols(); ++k) {
      for (std::size_t a = 0; a < n; ++a) in[a] = r(static_cast<Eigen::Index>(a), k);
      stage.decoupler.apply(in, out);
      for (std::size_t a = 0; a < n; ++a) (*own)(static_cast<Eigen::Index>(a), k) = out[a];
    }
  }
  std::vector<std::unique_ptr<sim::SignalGenerator>> out;
  out.reserve(n);
  for (std::size_t a = 0; a < n; ++a) {
    const Eigen::RowVectorXd row = own->row(static_cast<Eigen::Index>(a));
    out.push_back(sim::make_uniform_signal(std::vector<double>(row.begin(), row.end()), dt));
  }
  how["reach"] = own_reach(*own, stage.axes, ranges);
  return out;
}

// Runs each axis's preparation on its program, in turn, the progress spread over them.
RunPreparation joined(std::vector<RunPreparation> parts) {
  std::vector<RunPreparation> work;
  for (auto& p : parts) {
    if (p.work) work.push_back(std::move(p));
  }
  if (work.empty()) return {};
  std::string stage = work.front().stage + " of every axis";
  return {std::move(stage), [work = std::move(work)](RunProgram& program,
                                                     const std::function<void(double)>& progress) {
            const double n = static_cast<double>(program.axes());
            for (std::size_t a = 0; a < program.axes() && a < work.size(); ++a) {
              work[a].work(program.axis(a),
                           [&](double f) { progress((static_cast<double>(a) + f) / n); });
            }
          }};
}

// Each axis's reference, as track_reference() builds it from its upload (the built-in one's
// samples over that axis's range), with the uploads it was built from; refused when their
// lengths differ. Sets each request's upload name.
struct AxisReferences {
  std::vector<Upload> builtin;         ///< a built-in reference's, per axis
  std::vector<const Upload*> uploads;  ///< per axis, the upload its reference plays
  std::vector<TrackReference> refs;
};

AxisReferences axis_references(const StageTrackRequest& request,
                               const std::vector<RunContext>& contexts,
                               std::vector<TrackRequest>& requests,
                               std::span<const sim::AxisRange> ranges,
                               std::span<const Upload* const> uploads, double rate_hz) {
  AxisReferences out;
  out.uploads.assign(uploads.begin(), uploads.end());
  if (request.uploads.empty()) {
    out.builtin = builtin_uploads(request.builtin, ranges, rate_hz);
    out.uploads.clear();
    for (const Upload& u : out.builtin) out.uploads.push_back(&u);
  }
  out.refs.reserve(contexts.size());
  for (std::size_t a = 0; a < contexts.size(); ++a) {
    requests[a].reference_upload = out.uploads[a]->name;
    out.refs.push_back(track_reference(requests[a], contexts[a], out.uploads[a]));
    if (out.refs[a].samples != out.refs[0].samples) {
      throw CommandError("bad_params", "the axes' references last " +
                                           std::to_string(out.refs[0].samples) + " and " +
                                           std::to_string(out.refs[a].samples) +
                                           " ticks: a stage's axes play one reference together");
    }
  }
  return out;
}

json reference_json(const StageTrackRequest& request) {
  if (!request.uploads.empty()) return {{"kind", "upload"}, {"uploads", request.uploads}};
  return {{"kind", sim::to_string(request.builtin.kind)},
          {"frequencies_hz", request.builtin.frequencies_hz},
          {"range_fraction", request.builtin.span_fraction},
          {"duration_s", request.builtin.duration_s}};
}

json decoupling_json(const StageTrackRequest& request, const StageModel* stage, bool decoupled,
                     json dynamic) {
  if (decoupled) {
    return {{"static", true}, {"dynamic", std::move(dynamic)}, {"from_run", stage->run_id}};
  }
  return {{"static", false},
          {"dynamic", {{"used", false}, {"why_not", "no decoupling"}}},
          {"why_not", !request.decouple  ? "decouple = false"
                      : stage == nullptr ? "no stage model: identify first"
                                         : "the compensator has no feedforward"}};
}

// Each axis's feedforward target (null where the compensator takes the reference itself) and
// the result's `decoupling`.
struct StageTargets {
  std::vector<std::unique_ptr<sim::SignalGenerator>> signals;
  json decoupling = json::object();
};

StageTargets stage_targets(const StageTrackRequest& request, const StageModel* stage,
                           const std::vector<RunContext>& contexts,
                           std::span<const sim::AxisRange> ranges,
                           const std::vector<TrackReference>& refs, double dt) {
  const std::size_t n = contexts.size();
  const bool decoupled = request.decouple && stage != nullptr && stage->decoupler.axes() == n &&
                         hc::needs_model(request.common.compensator_kind);
  StageTargets out;
  out.signals.resize(n);
  json dynamic;
  if (decoupled) {
    out.signals = decoupled_targets(refs, *stage, contexts, ranges, request.dynamic, dt,
                                    refs[0].samples, dynamic);
  }
  json reach = json::object();
  if (dynamic.is_object() && dynamic.contains("reach")) {
    reach = std::move(dynamic["reach"]);
    dynamic.erase("reach");
  }
  out.decoupling = decoupling_json(request, stage, decoupled, std::move(dynamic));
  if (!reach.empty()) out.decoupling["beyond_reach"] = std::move(reach);
  return out;
}

// make_axis_track_program(); a learned drive refused for another built-in reference is named
// in the stage's words (its built-in references play as uploads, whose refusal speaks of files).
BuiltRun axis_track_program(const StageTrackRequest& stage, const TrackRequest& request,
                            const RunContext& ctx, const Upload* upload, TrackReference ref,
                            std::unique_ptr<sim::SignalGenerator> targets) {
  try {
    return make_axis_track_program(request, ctx, upload, std::move(ref), std::move(targets));
  } catch (const CommandError& e) {
    const std::string what = e.what();
    if (!stage.uploads.empty() || !request.learning.learned ||
        what.find("' was learned for ") == std::string::npos) {
      throw;
    }
    throw CommandError(e.code(), "learned: '" + *request.learning.learned +
                                     "-learned' was learned for another reference or range than "
                                     "this " +
                                     std::string(sim::to_string(stage.builtin.kind)) +
                                     ": a stage's learned drive replays only the reference it "
                                     "was learned on (the same reference, frequencies_hz, "
                                     "range_fraction and duration_s, and the same model's "
                                     "range), or learn this one with --learn N");
  }
}

// A stage's replay: every axis's lead-in ends at one period, trial 0 beginning together.
void decide_lead_ins_together(RunProgram& program) {
  TrackDrive& first = *track_drive(program);
  first.lead_in_together = std::make_unique<LearningExchange::LeadInTogether>();
  first.lead_in_together->axes = program.axes();
  for (std::size_t a = 0; a < program.axes(); ++a) {
    if (auto& l = track_drive(program.axis(a))->learning) {
      l->decide_together(first.lead_in_together.get());
    }
  }
}

// The stage track's header, reply and status: the run's reference, compensator and
// decoupling, each axis's own under `axes`.
void describe_stage_track(BuiltRun& run, const StageTrackRequest& request,
                          const std::vector<std::string>& names, json axis_headers,
                          json axis_replies, const json& decoupling, const RunContext& ctx) {
  const json reference = reference_json(request);
  run.header = {{"run",
                 {{"kind", "track"},
                  {"axes", names},
                  {"reference", reference},
                  {"compensator", request.common.compensator},
                  {"decoupling", decoupling},
                  {"rate_hz", ctx.settings.loop.rate_hz}}},
                {"driver", ctx.settings.driver_type},
                {"axes", std::move(axis_headers)}};
  run.reply = {{"axes", std::move(axis_replies)},
               {"reference", reference},
               {"compensator", request.common.compensator},
               {"decoupling", decoupling}};
  run.status = {{"compensator", request.common.compensator}, {"axes", names}};
}

// The learning run a stage's `learned` names (RUN, as its result's learned_drive gives it;
// RUN-learned is taken too), each of whose axes' drives is RUN-AXIS-learned. An axis's own
// drive is refused: the stage replays every axis.
std::string stage_learning_run(std::string name, std::span<const std::string> axes) {
  for (const std::string tail : {".json", ".csv", "-learned"}) {
    if (name.size() > tail.size() && name.ends_with(tail)) name.resize(name.size() - tail.size());
  }
  for (const std::string& axis : axes) {
    if (name.ends_with("-" + axis)) {
      throw CommandError("bad_params", "learned: on a stage, the learning run's id (" +
                                           name.substr(0, name.size() - axis.size() - 1) +
                                           "), which names every axis's drive, not one axis's");
    }
  }
  return name;
}

}  // namespace

std::vector<std::string> upload_per_axis(const json& uploads, const std::string& key,
                                         std::span<const std::string> axes, const std::string& what,
                                         const std::string& why) {
  // The message: the key, then what is wrong with it.
  const auto refuse = [&key](std::initializer_list<std::string_view> parts) {
    std::string message = key;
    for (const std::string_view part : parts) message.append(part);
    throw CommandError("bad_params", message);
  };
  if (!uploads.is_object()) refuse({": {axis: upload} naming every axis (", why, ")"});
  for (const auto& [axis, value] : uploads.items()) {
    if (std::find(axes.begin(), axes.end(), axis) == axes.end()) {
      refuse({": '", axis, "' is no axis of the stage"});
    }
    if (!value.is_string() || value.get<std::string>().empty()) {
      refuse({".", axis, ": an upload's name"});
    }
  }
  std::vector<std::string> names;
  for (const std::string& axis : axes) {
    if (!uploads.contains(axis)) refuse({": no ", what, " for axis '", axis, "' (", why, ")"});
    names.push_back(uploads[axis].get<std::string>());
  }
  return names;
}

StageTrackRequest parse_stage_track_request(const RequestParams& request, const RunContext& ctx,
                                            std::span<const std::string> axes) {
  StageTrackRequest r;
  for (const char* key : {"frequency_hz", "periods", "min_um", "max_um"}) {
    if (request.has(key)) {
      throw CommandError("bad_params", std::string(key) +
                                           ": a one-axis reference's key; a stage's reference "
                                           "takes frequencies_hz, range_fraction and duration_s");
    }
  }
  // The keys a stage's track reads itself left out; track's own parser reads the rest, as the
  // row of a built-in reference.
  json rest = request.params().is_object() ? request.params() : json::object();
  for (const char* key : {"reference", "frequencies_hz", "range_fraction", "duration_s", "decouple",
                          "decoupling", "reference_uploads", "approach_s"}) {
    rest.erase(key);
  }
  r.common = parse_track_request(RequestParams(rest, common::kTrackBuiltinParams), ctx);
  if (request.has("approach_s")) r.common.approach_s = request.number("approach_s");
  if (r.common.learning.learned) {
    const std::string run = stage_learning_run(*r.common.learning.learned, axes);
    for (const std::string& axis : axes)
      r.learned_drives.push_back(std::string(run).append("-").append(axis));
  }
  // Beside a learned drive each axis's loop corrects through the linear map (FeedbackGainsRequest).
  if (r.common.learning.trials > 0 || r.common.learning.learned) {
    r.common.gains.through_linear_map = true;
  }
  r.decouple = request.boolean("decouple");
  const std::string decoupling = request.string("decoupling");
  if (decoupling != "dynamic" && decoupling != "static") {
    throw CommandError("bad_params",
                       "decoupling: 'static' (the default: the coupling's gains) or 'dynamic' "
                       "(its paths' modes too, where identify's responses show them), not '" +
                           decoupling + "'");
  }
  r.dynamic = decoupling == "dynamic";
  const json& params = request.params();
  if (params.contains("reference_uploads")) {
    r.uploads = upload_per_axis(params["reference_uploads"], "reference_uploads", axes, "reference",
                                "a stage's reference names every axis");
    return r;
  }
  sim::StageReferenceKind kind;
  try {
    kind = sim::stage_reference_kind_from_string(request.string("reference", "raster"));
  } catch (const std::exception& e) {
    throw CommandError("bad_params", std::string("reference: ") + e.what());
  }
  r.builtin = builtin_defaults(kind, axes.size());
  if (params.contains("frequencies_hz")) {
    r.builtin.frequencies_hz.clear();
    for (const json& f : params["frequencies_hz"]) {
      if (!f.is_number() || !(f.get<double>() > 0.0) ||
          f.get<double>() > ctx.settings.loop.rate_hz / 20.0) {
        throw CommandError("bad_params", "frequencies_hz: each in (0, " +
                                             std::to_string(ctx.settings.loop.rate_hz / 20.0) +
                                             "] Hz (a twentieth of the loop rate)");
      }
      r.builtin.frequencies_hz.push_back(f.get<double>());
    }
  }
  r.builtin.span_fraction = request.number("range_fraction", r.builtin.span_fraction);
  r.builtin.duration_s = request.number("duration_s", r.builtin.duration_s);
  if (!(r.builtin.duration_s > 0.0)) throw CommandError("bad_params", "duration_s: must be > 0");
  return r;
}

BuiltRun make_stage_track_program(const StageTrackRequest& request, const RunContext& ctx,
                                  const StageModel* stage, std::span<const double> u_now,
                                  std::span<const Upload* const> uploads) {
  const std::size_t n = u_now.size();
  const double dt = ctx.dt();
  std::vector<RunContext> contexts;
  std::vector<TrackRequest> requests(n, request.common);
  std::vector<sim::AxisRange> ranges;
  for (std::size_t a = 0; a < n; ++a) {
    // Each axis starts from its own drive of the learning run (RUN-AXIS-learned).
    if (a < request.learned_drives.size()) requests[a].learning.learned = request.learned_drives[a];
    contexts.push_back(axis_context(ctx, stage, a, u_now[a]));
    const auto range = actuator_range(contexts.back());
    if (!range) {
      throw CommandError("no_range",
                         "no reference range for axis " + std::to_string(a) +
                             ": identify the stage first, or set limits.y_min and y_max");
    }
    ranges.push_back({range->y_bottom, range->y_top});
  }
  AxisReferences axis_refs =
      axis_references(request, contexts, requests, ranges, uploads, ctx.settings.loop.rate_hz);
  json designed_together = design_loops_together(request.common.compensator_kind,
                                                 request.common.gains, contexts, stage, dt);
  std::vector<TrackReference>& refs = axis_refs.refs;
  StageTargets targets = stage_targets(request, stage, contexts, ranges, refs, dt);
  const json& decoupling = targets.decoupling;

  BuiltRun run;
  std::vector<RunPreparation> preparations;
  std::vector<std::shared_ptr<const FeedbackPlan>> plans;
  json axis_headers = json::object(), axis_replies = json::object();
  std::vector<std::string> names;
  for (std::size_t a = 0; a < n; ++a) {
    const std::string name = stage != nullptr ? stage->axes[a] : std::to_string(a);
    names.push_back(name);
    BuiltRun axis = axis_track_program(request, requests[a], contexts[a], axis_refs.uploads[a],
                                       std::move(refs[a]), std::move(targets.signals[a]));
    axis_headers[name] = axis.header;
    axis_replies[name] = axis.reply;
    preparations.push_back(std::move(axis.preparation));
    plans.push_back(axis.feedback_plan);
    if (a == 0) {
      run.program = std::move(axis.program);
      run.learning = std::move(axis.learning);
    } else {
      run.program->stage_axes.push_back(std::move(axis.program));
      run.axis_learning.push_back(std::move(axis.learning));
    }
  }
  if (!request.learned_drives.empty()) decide_lead_ins_together(*run.program);
  describe_stage_track(run, request, names, std::move(axis_headers), std::move(axis_replies),
                       decoupling, ctx);
  run.program->summary["decoupling"] = decoupling;
  if (json interaction = feedback_interaction(stage, plans, dt); !interaction.is_null()) {
    if (!designed_together.is_null()) interaction["designed_together"] = designed_together;
    run.reply["feedback_interaction"] = interaction;
    run.program->summary["feedback_interaction"] = std::move(interaction);
  }
  // The stage's prediction couples the axes' models as the stage couples their motion.
  if (stage != nullptr && stage->decoupler.axes() == n) run.program->coupling = stage->decoupler;
  run.preparation = joined(std::move(preparations));
  return run;
}

json stage_tune(const RunContext& ctx, const StageModel* stage, std::span<const double> u_now,
                std::span<const std::string> axes, hc::CompensatorKind kind,
                const FeedbackGainsRequest& gains) {
  const std::size_t n = u_now.size();
  std::vector<RunContext> contexts;
  for (std::size_t a = 0; a < n; ++a) contexts.push_back(axis_context(ctx, stage, a, u_now[a]));
  json designed_together = design_loops_together(kind, gains, contexts, stage, ctx.dt());
  json out = {{"axes", json::object()}};
  std::vector<std::shared_ptr<const FeedbackPlan>> plans;
  for (std::size_t a = 0; a < n; ++a) {
    // The plan design_loops_together() kept (lowered where it had to be), or designed here.
    plans.push_back(std::make_shared<const FeedbackPlan>(plan_feedback(contexts[a], kind, gains)));
    json axis = plans.back()->summary;
    axis["curves"] = loop_curves(*plans.back(), ctx.dt());
    out["axes"][a < axes.size() ? axes[a] : std::to_string(a)] = std::move(axis);
  }
  json interaction = feedback_interaction(stage, plans, ctx.dt());
  if (!interaction.is_null() && !designed_together.is_null()) {
    interaction["designed_together"] = std::move(designed_together);
  }
  if (!interaction.is_null()) out["feedback_interaction"] = std::move(interaction);
  return out;
}

}  // namespace hystbench::daemon::details
