// A stage's identify: one axis at a time, then compensation::fit_stage (stage_runs.hpp).
#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <string>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/fit_families.hpp"
#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/daemon/runs/identification_fit.hpp"
#include "runs/details/stage_runs.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;
namespace hc = hystbench::compensation;

namespace {

// The ramps into and out of each turn [s]: the held axes see the moved one's ramp back before
// the next turn begins, outside every record the fit reads.
constexpr double kRampS = 0.1;

// Axis a's drive over the whole run: its present output, its turn, its present output again.
std::vector<double> axis_drive(const sim::Excitation& exc, std::size_t a, std::size_t axes,
                               double u_hold, std::size_t ramp) {
  const std::size_t turn = 2 * ramp + exc.samples.size();
  std::vector<double> u;
  u.reserve(turn * axes);
  u.assign(turn * a, u_hold);
  append_ramp(u, u_hold, exc.samples.front(), ramp);
  u.insert(u.end(), exc.samples.begin(), exc.samples.end());
  append_ramp(u, exc.samples.back(), u_hold, ramp);
  u.resize(turn * axes, u_hold);
  return u;
}

// "y<-x": the share of x's motion on y.
std::string pair_name(const std::string& to, const std::string& from) { return to + "<-" + from; }

// Each turn's record: the moved axis's drive and every axis's output (`ys`, each put at the
// output it answers) over its first `samples`.
std::vector<hc::OneAxisMotion> turn_records(const RunProgram& run,
                                            std::span<const std::vector<double>> ys,
                                            std::size_t turn, std::size_t samples, double dt) {
  const std::size_t axes = ys.size();
  std::vector<hc::OneAxisMotion> records;
  records.reserve(axes);
  for (std::size_t moved = 0; moved < axes; ++moved) {
    hc::OneAxisMotion m;
    m.moved = moved;
    m.dt = dt;
    m.outputs.resize(static_cast<Eigen::Index>(axes), static_cast<Eigen::Index>(samples));
    const std::size_t from = moved * turn;
    for (std::size_t b = 0; b < axes; ++b) {
      const std::vector<double>& y = ys[b];
      for (std::size_t k = 0; k < samples; ++k) {
        m.outputs(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(k)) = y[from + k];
      }
    }
    const auto& u = run.axis(moved).records.u;
    m.drive.assign(u.begin() + static_cast<std::ptrdiff_t>(from),
                   u.begin() + static_cast<std::ptrdiff_t>(from + samples));
    records.push_back(std::move(m));
  }
  return records;
}

// The coupling's gains for identify's result, keyed "y<-x".
json coupling_json(const hc::CouplingEstimate& coupling, std::span<const std::string> axes) {
  json gains = json::object();
  for (std::size_t i = 0; i < axes.size(); ++i) {
    for (std::size_t j = 0; j < axes.size(); ++j) {
      if (i == j) continue;
      const auto ii = static_cast<Eigen::Index>(i), jj = static_cast<Eigen::Index>(j);
      const double g = coupling.gains(ii, jj);
      const double db = hc::gain_db(g);
      gains[pair_name(axes[i], axes[j])] = {{"gain", g},
                                            {"db", std::isfinite(db) ? json(db) : json(nullptr)},
                                            {"residual_share", coupling.residual_share(ii, jj)}};
    }
  }
  return {{"gains", gains},
          {"meaning",
           "\"y<-x\": the share of x's own displacement that reaches y at low frequency; "
           "residual_share: what a static gain leaves of it"}};
}

// The stage every axis's model file carries: its axes, its identify run and the coupling.
json stage_json(const hc::CouplingEstimate& coupling, std::span<const std::string> axes,
                const std::string& run_id) {
  json gains = json::array(), shares = json::array();
  for (Eigen::Index i = 0; i < coupling.gains.rows(); ++i) {
    json g = json::array(), r = json::array();
    for (Eigen::Index j = 0; j < coupling.gains.cols(); ++j) {
      g.push_back(coupling.gains(i, j));
      r.push_back(coupling.residual_share(i, j));
    }
    gains.push_back(std::move(g));
    shares.push_back(std::move(r));
  }
  return {{"axes", std::vector<std::string>(axes.begin(), axes.end())},
          {"run_id", run_id},
          {"coupling", {{"gains", gains}, {"residual_share", shares}}}};
}

// stage_json()'s coupling back, `n` axes square; throws naming what is wrong.
hc::CouplingEstimate coupling_from_json(const json& j, std::size_t n) {
  hc::CouplingEstimate c;
  const auto n_idx = static_cast<Eigen::Index>(n);
  c.gains = Eigen::MatrixXd::Zero(n_idx, n_idx);
  c.residual_share = Eigen::MatrixXd::Zero(n_idx, n_idx);
  for (const auto& [key, m] :
       {std::pair{"gains", &c.gains}, {"residual_share", &c.residual_share}}) {
    const json& rows = j.at(key);
    if (!rows.is_array() || rows.size() != n) {
      throw std::invalid_argument(std::string(key) + ": " + std::to_string(n) + " rows expected");
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (!rows[i].is_array() || rows[i].size() != n) {
        throw std::invalid_argument(std::string(key) + "[" + std::to_string(i) +
                                    "]: " + std::to_string(n) + " numbers expected");
      }
      for (std::size_t k = 0; k < n; ++k) {
        (*m)(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) = rows[i][k].get<double>();
      }
    }
  }
  return c;
}

// identify's fit options for each axis of a stage, at the fit rate.
hc::StageFitOptions stage_fit_options(const json& fit, const BenchSettings& settings) {
  hc::StageFitOptions options;
  options.stride = std::max<std::size_t>(
      1, static_cast<std::size_t>(
             std::llround(settings.loop.rate_hz / settings.identify.fit_rate_hz)));
  options.axis.kind = common::parse_fit_family(fit.value("model", ""));
  options.axis.operators = fit.value("operators", 0);
  options.axis.dead_zones = fit.value("dead_zones", -1);
  options.axis.heldout_fraction = settings.identify.heldout_fraction;
  options.axis.drift = true;  // the creep of the turns before still settles
  options.axis.creep = options.axis.kind == hc::ModelKind::kPreisach;
  // No delay at the fit rate: a tick or two of the driver's exchange is a fraction of a fit
  // sample there, which a whole sample of delay overstates (fit_identification_record's reason).
  options.axis.delay_samples = 0;
  const auto skip = fit.value("skip_samples", std::size_t{0});
  options.axis.skip_samples = (skip + options.stride - 1) / options.stride;
  return options;
}

}  // namespace

std::string stage_model_file(const std::string& run_id, const std::string& axis) {
  std::string name = run_id;
  name.append("-").append(axis).append(".json");
  return name;
}

RunContext axis_context(const RunContext& ctx, const StageModel* stage, std::size_t a,
                        double u_now) {
  RunContext c = ctx;
  c.model = stage != nullptr && a < stage->models.size() ? &stage->models[a] : nullptr;
  c.u_now = u_now;
  c.plans = nullptr;
  c.model_state = nullptr;  // an axis's model is not the bench's active one
  c.responses = nullptr;
  c.feedback_plans = nullptr;
  ++c.model_generation;
  return c;
}

BuiltRun make_stage_identify_program(const IdentifyRequest& request, const RunContext& ctx,
                                     std::span<const std::string> axes,
                                     std::span<const double> u_now) {
  const BenchSettings& s = ctx.settings;
  const sim::Excitation exc = identify_excitation(request, ctx);
  const auto ramp = static_cast<std::size_t>(std::ceil(kRampS / ctx.dt()));
  const std::size_t turn = 2 * ramp + exc.samples.size();
  const std::size_t total = turn * axes.size();
  if (total > kMaxRecordedSamples) {
    throw common::CommandError(
        "bad_params", "identify on a stage of " + std::to_string(axes.size()) + " axes lasts " +
                          std::to_string(total) + " ticks, more than the bench records (" +
                          std::to_string(kMaxRecordedSamples) +
                          "): lower [identify] cycles, settle_s or the loop rate");
  }
  std::unique_ptr<RunProgram> first;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    const RunContext axis_ctx = axis_context(ctx, nullptr, a, u_now[a]);
    auto p = std::make_unique<RunProgram>();
    p->kind = RunKind::kIdentify;
    p->excitation = axis_drive(exc, a, axes.size(), u_now[a], ramp);
    p->total_samples = total;
    p->metrics_from = 0;
    p->model = predictor(axis_ctx, u_now[a]);
    p->summary["y_model"] = predictor_name(axis_ctx);
    p->summary["y_model_from"] = predictor_source(axis_ctx);
    // Scored from the axis's own major loop: before it, its model has not met its state.
    const sim::ExcitationSegment* major = exc.find("major_loop");
    p->model_metrics_from = turn * a + ramp + (major != nullptr ? major->begin : 0);
    allocate_records(*p, true);  // with each reading's response: the fit aligns them
    if (a == 0) {
      first = std::move(p);
    } else {
      first->stage_axes.push_back(std::move(p));
    }
  }
  json segments = json::array();
  for (const auto& seg : exc.segments) {
    segments.push_back({{"name", seg.name}, {"begin", seg.begin + ramp}, {"end", seg.end + ramp}});
  }
  const sim::ExcitationSegment* major = exc.find("major_loop");
  BuiltRun run;
  run.program = std::move(first);
  const json names(std::vector<std::string>(axes.begin(), axes.end()));
  run.header = {{"run",
                 {{"kind", "identify"},
                  {"axes", names},
                  {"turn_samples", turn},
                  {"model", request.model},
                  {"u_min", request.u_min},
                  {"u_max", request.u_max},
                  {"rate_hz", s.loop.rate_hz},
                  {"segments_of_each_turn", segments}}},
                {"driver", s.driver_type},
                {"y_model", predictor_name(ctx)}};
  run.reply = {{"axes", names},
               {"one_axis_at_a_time", true},
               {"turn_s", static_cast<double>(turn) * ctx.dt()}};
  run.fit = {{"model", request.model},
             {"operators", request.operators},
             {"dead_zones", request.dead_zones},
             {"axes", names},
             {"turn_samples", turn},
             {"record_samples", ramp + exc.samples.size()},
             {"skip_samples", ramp + (major != nullptr ? major->begin : 0)},
             {"u_min", request.u_min},
             {"u_max", request.u_max}};
  return run;
}

StageModel fit_stage_identify(const RunProgram& run, const json& fit,
                              const BenchSettings& settings) {
  const std::vector<std::string> axes = fit.at("axes").get<std::vector<std::string>>();
  const auto turn = fit.at("turn_samples").get<std::size_t>();
  const auto samples = fit.at("record_samples").get<std::size_t>();
  const double dt = 1.0 / settings.loop.rate_hz;
  if (run.axes() != axes.size() || run.records.count < turn * axes.size()) {
    throw common::CommandError("fit_error", "the stage's identify record is incomplete (" +
                                                std::to_string(run.records.count) + " of " +
                                                std::to_string(turn * axes.size()) + " samples)");
  }
  // Each axis's readings put at the outputs they answer (a thread-mode Modbus exchange answers
  // an earlier tick's), as a one-axis identify does; the model then carries that latency as
  // its delay, which the feedforward previews.
  std::vector<std::vector<double>> ys(axes.size());
  std::vector<int> exchange_ticks(axes.size(), 0);
  for (std::size_t b = 0; b < axes.size(); ++b) {
    const RunRecords& r = run.axis(b).records;
    const std::size_t n = std::min<std::size_t>(r.count, r.y.size());
    const std::span<const double> u(r.u.data(), std::min(n, r.u.size()));
    const std::span<const double> y(r.y.data(), n);
    const std::span<const std::uint32_t> response(r.response.data(),
                                                  std::min(n, r.response.size()));
    ys[b] = response.empty() ? std::vector<double>(y.begin(), y.end())
                             : align_to_outputs(u, y, response);
    exchange_ticks[b] = median_response_ticks(response);
  }
  const std::vector<hc::OneAxisMotion> records = turn_records(run, ys, turn, samples, dt);
  const hc::StageFitOptions options = stage_fit_options(fit, settings);
  hc::StageFit stage_fit;
  try {
    stage_fit = hc::fit_stage(records, options);
  } catch (const std::exception& e) {
    throw common::CommandError("fit_error", e.what());
  }
  StageModel model;
  model.axes = axes;
  model.run_id = run.run_id;
  model.coupling = stage_fit.coupling;
  try {
    model.decoupler = hc::StageDecoupler(stage_fit.coupling.gains);
  } catch (const std::exception& e) {
    throw common::CommandError("fit_error",
                               std::string("the coupling cannot be taken out: ") + e.what());
  }
  json per_axis = json::object();
  for (std::size_t a = 0; a < axes.size(); ++a) {
    hc::FitResult& f = stage_fit.axes[a];
    f.model.input_min = fit.value("u_min", settings.loop.limits.u_min);
    f.model.input_max = fit.value("u_max", settings.loop.limits.u_max);
    if (exchange_ticks[a] > 0) {
      f.delay_samples = exchange_ticks[a];
      f.model.set_delay(static_cast<double>(exchange_ticks[a]) * dt);
      f.notes.push_back("delay " + std::to_string(exchange_ticks[a]) +
                        " ticks: the driver's exchange (its readings' median response_ticks)");
    }
    const Eigen::RowVectorXd own = records[a].outputs.row(static_cast<Eigen::Index>(a));
    const double range = own.maxCoeff() - own.minCoeff();
    const json figures = {
        {"model", std::string(hc::to_string(f.model.hysteresis().kind()))},
        {"operators", f.operators},
        {"heldout_rms_error_um", f.heldout.rmse},
        {"heldout_rms_error_percent", hc::percent_of_range(f.heldout.rmse, range)},
        {"fit_rms_error_um", f.fit.rmse},
        {"range_um", range},
        {"delay_samples", f.delay_samples},
        {"creep", f.creep},
        {"notes", f.notes}};
    per_axis[axes[a]] = figures;
    hc::ModelFile file{
        std::move(f.model),
        {{"run_id", run.run_id},
         {"stage_axis", axes[a]},
         {"fit_rate_hz", settings.loop.rate_hz / static_cast<double>(options.stride)},
         {"figures", figures}}};
    model.models.push_back(std::move(file));
  }
  const json stage = stage_json(model.coupling, axes, run.run_id);
  for (hc::ModelFile& file : model.models) file.identification["stage"] = stage;
  model.report = {{"axes", per_axis}, {"coupling", coupling_json(model.coupling, axes)}};
  return model;
}

StageModel stage_model_from_files(std::vector<hc::ModelFile> files,
                                  std::span<const std::string> axes,
                                  std::span<const std::string> names) {
  const auto refuse = [&](std::size_t a, const std::string& why) {
    throw common::CommandError("bad_model", names[a] + ": " + why);
  };
  StageModel model;
  model.axes.assign(axes.begin(), axes.end());
  json per_axis = json::object();
  for (std::size_t a = 0; a < files.size(); ++a) {
    const json& id = files[a].identification;
    if (!id.contains("stage") || id.value("stage_axis", "") != axes[a]) {
      refuse(a, "not axis " + axes[a] +
                    "'s model of a stage identify (no identification.stage "
                    "naming it)");
    }
    const json& stage = id["stage"];
    if (stage.value("axes", json::array()) != json(model.axes)) {
      refuse(a, "a model of a stage of axes " + stage.value("axes", json::array()).dump() +
                    ", this bench's are " + json(model.axes).dump());
    }
    if (a == 0) {
      model.run_id = stage.value("run_id", "");
      try {
        model.coupling = coupling_from_json(stage.at("coupling"), axes.size());
        model.decoupler = hc::StageDecoupler(model.coupling.gains);
      } catch (const std::exception& e) {
        refuse(a, std::string("its coupling: ") + e.what());
      }
    } else if (stage.value("run_id", "") != model.run_id) {
      refuse(a, "of stage identify " + stage.value("run_id", "") + ", " + names[0] + " of " +
                    model.run_id + ": load one identify's models together");
    }
    per_axis[axes[a]] = id.value("figures", json::object());
  }
  // The cross responses each file kept (what the other axes' drives left on its axis).
  const std::size_t n = axes.size();
  model.cross.assign(n, std::vector<hc::StageResponses>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const json cross = files[i].identification["stage"].value("cross_responses", json::object());
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j || !cross.contains(axes[j])) continue;
      try {
        model.cross[i][j] = hc::stage_responses_from_json(
            cross[axes[j]], "identification.stage.cross_responses." + axes[j]);
      } catch (const std::exception& e) {
        refuse(i, e.what());
      }
    }
  }
  model.models = std::move(files);
  model.report = {{"axes", per_axis},
                  {"coupling", coupling_json(model.coupling, axes)},
                  {"loaded_from", json(std::vector<std::string>(names.begin(), names.end()))}};
  return model;
}

}  // namespace hystbench::daemon::details
