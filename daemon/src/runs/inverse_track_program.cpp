#include "hystbench/daemon/runs/inverse_track_program.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "hystbench/compensation/dynamics_inversion.hpp"
#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/tracking_metrics.hpp"
#include "hystbench/sim/signal_generator.hpp"

namespace hystbench::daemon {

namespace hc = compensation;

namespace {

// Ramps linearly from a to b over n samples (b reached on the last one).
void append_ramp(std::vector<double>& out, double a, double b, std::size_t n) {
  for (std::size_t k = 1; k <= n; ++k) out.push_back(a + (b - a) * static_cast<double>(k) / n);
}

}  // namespace

ModelOutputRange major_loop_range(const hc::ActuatorModel& model, double u_min, double u_max,
                                  double dt_s) {
  hc::ActuatorModel m = model;
  m.configure(dt_s);
  m.reset(u_min);
  const std::size_t n = 2000;
  ModelOutputRange r{INFINITY, -INFINITY};
  for (std::size_t k = 0; k <= n; ++k)
    r.y_top = std::max(r.y_top, m.step(u_min + (u_max - u_min) * k / n));
  for (std::size_t k = 0; k <= n; ++k)
    r.y_bottom = std::min(r.y_bottom, m.step(u_max - (u_max - u_min) * k / n));
  return r;
}

std::vector<double> precondition_sweep(double u_now, double u_min, double u_max,
                                       double precondition_s, double dt_s) {
  std::vector<double> out;
  const std::size_t half = static_cast<std::size_t>(std::ceil(0.5 * precondition_s / dt_s));
  if (half > 0) {
    out.reserve(2 * half);
    append_ramp(out, u_now, u_max, half);
    append_ramp(out, u_max, u_min, half);
  }
  return out;
}

void arm_tare(TrackDrive& track, std::size_t sweep_samples, std::uint64_t model_exchange_ticks) {
  const std::size_t half = sweep_samples / 2;
  track.program.tare.from = half < 10 ? std::numeric_limits<std::uint64_t>::max()
                                      : half + half / 5;  // skip the turn's transient
  track.program.tare.model_exchange_ticks = model_exchange_ticks;
}

hc::ActuatorModel model_after(const hc::ActuatorModel& model, std::span<const double> prefix,
                              double u_start, double u_min, double u_max, double dt_s) {
  hc::ActuatorModel m = model;
  m.configure(dt_s);
  m.reset(prefix.empty() ? u_start : prefix.front());
  return model_after(std::move(m), prefix, u_min, u_max);
}

hc::ActuatorModel model_after(hc::ActuatorModel m, std::span<const double> prefix, double u_min,
                              double u_max) {
  for (const double u : prefix) m.step(u);
  if (m.input_max <= m.input_min) {
    m.input_min = u_min;
    m.input_max = u_max;
  }
  m.input_min = std::max(m.input_min, u_min);
  m.input_max = std::min(m.input_max, u_max);
  return m;
}

std::unique_ptr<RunProgram> make_verification_program(const hc::ActuatorModel& model,
                                                      const VerificationSpec& spec, double u_now,
                                                      const OutputLimits& limits, double dt_s) {
  if (!(spec.frequency_hz > 0.0) || !(spec.periods >= 1.0) ||
      !(spec.range_fraction > 0.0 && spec.range_fraction <= 1.0) || !(spec.precondition_s >= 0.0)) {
    throw std::invalid_argument("verification: bad segment specification");
  }
  const ModelOutputRange range = major_loop_range(model, limits.u_min, limits.u_max, dt_s);
  const double span = range.y_top - range.y_bottom;
  sim::SignalSpec ref;
  ref.kind = spec.reference == VerificationSpec::Reference::kSine ? sim::SignalKind::kSine
                                                                  : sim::SignalKind::kTriangle;
  ref.frequency_hz = spec.frequency_hz;
  ref.amplitude = 0.5 * spec.range_fraction * span;
  ref.offset = 0.5 * (range.y_bottom + range.y_top);
  ref.phase_rad = -M_PI / 2.0;  // start at the bottom of the range, rising, as `track` does
  ref.duration_s = spec.periods / spec.frequency_hz;

  auto p = std::make_unique<RunProgram>();
  p->kind = RunKind::kTrack;
  TrackDrive& track = make_track_drive(*p);
  track.program.reference = sim::make_signal_generator(ref);
  p->excitation = precondition_sweep(u_now, limits.u_min, limits.u_max, spec.precondition_s, dt_s);
  const hc::ActuatorModel m =
      model_after(model, p->excitation, u_now, limits.u_min, limits.u_max, dt_s);
  const hc::LinearMap linear{span / (limits.u_max - limits.u_min),
                             range.y_bottom - span / (limits.u_max - limits.u_min) * limits.u_min};
  track.program.compensator.emplace(hc::CompensatorKind::kInverse, hc::make_inverse(m),
                                    std::nullopt, linear);
  // As `track`: the model predicts y in every sample, and its delay and dynamics are inverted
  // from the previewed reference.
  hc::ActuatorModel predictor = model;
  predictor.configure(dt_s);
  predictor.reset(p->excitation.empty() ? u_now : p->excitation.front());
  p->model = std::move(predictor);
  const hc::DynamicsInversion inversion(model, dt_s, spec.feedforward_bandwidth_hz);
  if (inversion.active()) track.program.preview = inversion;
  arm_tare(track, p->excitation.size(), spec.model_exchange_ticks);
  const std::uint64_t prefix = p->excitation.size();
  const auto body = static_cast<std::uint64_t>(std::llround(ref.duration_s / dt_s));
  const auto one_period = static_cast<std::uint64_t>(std::llround(1.0 / spec.frequency_hz / dt_s));
  p->total_samples = prefix + body;
  p->metrics_from = prefix + (body >= 2 * one_period ? one_period : 0);
  track.program.y_ref_min = range.y_bottom;
  track.program.y_ref_max = range.y_top;
  p->records.capacity = p->total_samples - p->metrics_from;
  p->records.u.resize(p->records.capacity);
  p->records.y.resize(p->records.capacity);
  p->records.yr.resize(p->records.capacity);
  return p;
}

nlohmann::json tracking_error_json(const RunProgram& run) {
  nlohmann::json r = nlohmann::json::object();
  const std::size_t n = run.records.count;
  if (n <= 2) return r;
  std::span<const double> yr(run.records.yr.data(), n), y(run.records.y.data(), n);
  const hc::ErrorStats e = hc::error_stats(yr, y);  // range = reference span
  const double rms = run.error.rms();
  r["rms_error_um"] = rms;
  r["max_error_um"] = run.error.max;
  r["max_error_index"] = run.error.max_index;
  r["range_um"] = e.range;
  r["rms_error_percent"] = compensation::percent_of_range(rms, e.range);
  r["max_error_percent"] = compensation::percent_of_range(run.error.max, e.range);
  r["hysteresis_percent"] = hc::hysteresis_percent(yr, y);
  r["error_samples"] = run.error.samples;
  if (const TrackDrive* track = track_drive(run)) {
    const TareMeasure& tare = track->state().tare;
    if (tare.samples > 0) r["tare_um"] = tare.um();
    if (tare.startup_samples > 0) r["startup_offset_um"] = tare.startup_um();
  }
  // A reference that steps (a tenth of its span or more between two ticks): how y answered.
  const hc::StepFigures steps = hc::step_figures(yr, y, run.dt_s, 0.1 * e.range);
  if (steps.steps > 0) {
    r["step"] = {{"steps", steps.steps},
                 {"size_um", steps.mean_size},
                 {"size_percent", compensation::percent_of_range(steps.mean_size, e.range)},
                 {"settling_ms",
                  {{"max", 1e3 * steps.max_settling_s}, {"mean", 1e3 * steps.mean_settling_s}}},
                 {"overshoot_percent",
                  {{"max", 100.0 * steps.max_overshoot}, {"mean", 100.0 * steps.mean_overshoot}}},
                 {"band_percent", 1.0},
                 {"settled", steps.settled}};
  }
  return r;
}

}  // namespace hystbench::daemon
