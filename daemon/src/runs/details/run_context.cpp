#include "runs/details/run_context.hpp"

#include <algorithm>
#include <cmath>

#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"

namespace hystbench::daemon::details {

namespace hc = compensation;

std::optional<ActuatorRange> actuator_range(const RunContext& ctx) {
  const BenchSettings& s = ctx.settings;
  if (ctx.model != nullptr) {
    const auto& lim = s.loop.limits;
    const ModelOutputRange r = major_loop_range(ctx.model->model, lim.u_min, lim.u_max, ctx.dt());
    return ActuatorRange{r.y_bottom, r.y_top};
  }
  if (s.y_max > s.y_min) return ActuatorRange{s.y_min, s.y_max};
  return std::nullopt;
}

std::optional<hc::ActuatorModel> predictor(const RunContext& ctx, double u0) {
  const BenchSettings& s = ctx.settings;
  const auto& lim = s.loop.limits;
  std::optional<hc::ActuatorModel> m;
  if (ctx.model != nullptr && ctx.model_state != nullptr) return *ctx.model_state;
  if (ctx.model != nullptr) {
    m = ctx.model->model;
  } else if (s.y_max > s.y_min && lim.u_max > lim.u_min) {
    // No model yet: the configured range as a straight line, what `none` compensates with.
    const double gain = (s.y_max - s.y_min) / (lim.u_max - lim.u_min);
    m.emplace(
        std::make_unique<hc::PiModel>(hc::PiParameters{{0.0}, {gain}, s.y_min - gain * lim.u_min}));
  } else {
    return std::nullopt;
  }
  m->configure(ctx.dt());
  m->reset(u0);
  return m;
}

hc::ActuatorModel model_at_start(const RunContext& ctx, std::span<const double> prefix) {
  const auto& lim = ctx.settings.loop.limits;
  if (ctx.model_state != nullptr)
    return model_after(*ctx.model_state, prefix, lim.u_min, lim.u_max);
  return model_after(ctx.model->model, prefix, ctx.u_now, lim.u_min, lim.u_max, ctx.dt());
}

void describe_predictor(const RunContext& ctx, nlohmann::json& summary) {
  summary["y_model"] = predictor_name(ctx);
  summary["y_model_from"] = predictor_source(ctx);
  if (ctx.model == nullptr) return;
  summary["model_start"] = ctx.model_state != nullptr ? "history" : "relaxed";
  if (ctx.model_state != nullptr) summary["model_history_s"] = ctx.model_history_s;
}

nlohmann::json model_header(const RunContext& ctx) {
  if (ctx.model == nullptr) return nullptr;
  compensation::ModelFile header = *ctx.model;
  header.responses.reset();
  return compensation::to_json(header);
}

const char* predictor_name(const RunContext& ctx) {
  if (ctx.model != nullptr && ctx.model_state != nullptr) {
    return "the active model from the state the bench's output history left, stepped with u";
  }
  if (ctx.model != nullptr) return "the active model relaxed at the first output, stepped with u";
  if (ctx.settings.y_max > ctx.settings.y_min) {
    return "linear map of limits.y_min..y_max, stepped with u";
  }
  return "none (NaN): no model and no limits.y_min/y_max";
}

const char* predictor_source(const RunContext& ctx) {
  if (ctx.model != nullptr) return "model";
  return ctx.settings.y_max > ctx.settings.y_min ? "limits" : "none";
}

std::uint64_t model_exchange_ticks(const RunContext& ctx) {
  if (ctx.model == nullptr || !ctx.model->identification.is_object()) return 0;
  return static_cast<std::uint64_t>(
      std::max<std::int64_t>(0, ctx.model->identification.value("exchange_ticks", 0)));
}

std::uint64_t model_delay_ticks(const RunContext& ctx) {
  if (ctx.model == nullptr) return 0;
  const auto total =
      static_cast<std::int64_t>(std::ceil(ctx.model->model.delay_s() / ctx.dt() - 1e-9));
  // The driver's exchange latency is part of the identified delay, and each reading reports it.
  const auto exchange = static_cast<std::int64_t>(model_exchange_ticks(ctx));
  return static_cast<std::uint64_t>(std::max<std::int64_t>(0, total - exchange));
}

void append_ramp(std::vector<double>& out, double a, double b, std::size_t n) {
  for (std::size_t k = 1; k <= n; ++k) out.push_back(a + (b - a) * static_cast<double>(k) / n);
}

void allocate_records(RunProgram& p, bool responses) {
  p.records.capacity =
      std::min<std::uint64_t>(p.total_samples - p.metrics_from, kMaxRecordedSamples);
  p.records.u.resize(p.records.capacity);
  p.records.y.resize(p.records.capacity);
  p.records.yr.resize(p.records.capacity);
  if (responses) p.records.response.resize(p.records.capacity);
}

}  // namespace hystbench::daemon::details
