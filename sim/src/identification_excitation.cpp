#include "hystbench/sim/identification_excitation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "hystbench/compensation/number_text.hpp"
#include "hystbench/sim/signal_generator.hpp"

namespace hystbench::sim {

namespace {

void require_excitation(bool ok, const std::string& field, const std::string& what) {
  if (!ok) throw std::invalid_argument("identification_excitation: " + field + ": " + what);
}

void require_positive_excitation(double value, const std::string& field) {
  require_excitation(std::isfinite(value) && value > 0.0, field, "must be > 0");
}

std::string indexed(const std::string& field, std::size_t k) {
  return field + "[" + std::to_string(k) + "]";
}

void require_fraction_excitation(double value, const std::string& field) {
  require_excitation(value >= 0.0 && value <= 1.0, field, "must be in [0, 1]");
}

/// Cosine cycles from `low` up to `low + span` and back, starting and ending at `low`.
SignalSpec cycles_from_bottom(double low, double span, double frequency_hz, double cycles) {
  SignalSpec spec;
  spec.kind = SignalKind::kSine;
  spec.amplitude = 0.5 * span;
  spec.offset = low + 0.5 * span;
  spec.frequency_hz = frequency_hz;
  spec.phase_rad = -0.5 * std::numbers::pi;
  spec.duration_s = cycles / frequency_hz;
  return spec;
}

void validate(double range_min, double range_max, double dt_s,
              const IdentificationExcitationOptions& o) {
  require_excitation(std::isfinite(range_min) && std::isfinite(range_max) && range_max > range_min,
                     "range_max", "must be a finite number greater than range_min");
  require_positive_excitation(dt_s, "dt_s");
  require_excitation(std::isfinite(o.precondition_s) && o.precondition_s >= 0.0, "precondition_s",
                     "must be >= 0");
  require_excitation(std::isfinite(o.settle_s) && o.settle_s >= 0.0, "settle_s", "must be >= 0");
  require_positive_excitation(o.major_loop_frequency_hz, "major_loop_frequency_hz");
  require_excitation(o.major_loop_cycles >= 1, "major_loop_cycles", "must be >= 1");
  require_positive_excitation(o.minor_loop_frequency_hz, "minor_loop_frequency_hz");
  require_excitation(o.minor_loops >= 0, "minor_loops", "must be >= 0");
  require_excitation(o.rate_cycles.size() == o.rate_frequencies_hz.size(), "rate_cycles",
                     "needs one entry per rate_frequencies_hz entry");
  for (std::size_t k = 0; k < o.rate_frequencies_hz.size(); ++k) {
    require_positive_excitation(o.rate_frequencies_hz[k], indexed("rate_frequencies_hz", k));
    require_excitation(o.rate_cycles[k] >= 1, indexed("rate_cycles", k), "must be >= 1");
  }
  require_excitation(o.rate_span_fraction > 0.0 && o.rate_span_fraction <= 1.0,
                     "rate_span_fraction", "must be in (0, 1]");
  for (std::size_t k = 0; k < o.reversal_points.size(); ++k) {
    require_fraction_excitation(o.reversal_points[k], indexed("reversal_points", k));
  }
  require_positive_excitation(o.reversal_rate_fraction_per_s, "reversal_rate_fraction_per_s");
  for (std::size_t k = 0; k < o.hold_levels.size(); ++k) {
    require_fraction_excitation(o.hold_levels[k], indexed("hold_levels", k));
  }
  require_positive_excitation(o.hold_s, "hold_s");
  require_excitation(o.min_samples_per_period >= 2, "min_samples_per_period", "must be >= 2");

  double fastest_hz = std::max(o.major_loop_frequency_hz, o.minor_loop_frequency_hz);
  for (const double f : o.rate_frequencies_hz) fastest_hz = std::max(fastest_hz, f);
  require_excitation(dt_s * fastest_hz * o.min_samples_per_period <= 1.0, "dt_s",
                     "too coarse: fewer than " + std::to_string(o.min_samples_per_period) +
                         " samples per period at " + compensation::significant(fastest_hz, 6) +
                         " Hz");
}

class ExcitationBuilder {
 public:
  ExcitationBuilder(double range_min, double range_max, double dt_s)
      : min_(range_min), max_(range_max) {
    excitation_.dt_s = dt_s;
  }

  void append(const std::string& name, const SignalSpec& spec) {
    const auto values = sample_signal(*make_signal_generator(spec), excitation_.dt_s);
    ExcitationSegment segment{name, excitation_.samples.size(), 0};
    for (const double v : values) excitation_.samples.push_back(std::clamp(v, min_, max_));
    segment.end = excitation_.samples.size();
    if (segment.end > segment.begin) excitation_.segments.push_back(std::move(segment));
  }

  Excitation finish() && { return std::move(excitation_); }

 private:
  double min_;
  double max_;
  Excitation excitation_;
};

// The settle hold and the precondition sweep, as far as the options ask for them.
// Settle at mid-range first: creep lags approach the level the record works around, so what ran
// before leaves little creep transient in it. Then the sweep, from where the settle left the
// input, wipes the hysteresis memory and ends at range_min.
void append_settle_and_sweep(ExcitationBuilder& builder, double range_min, double span,
                             const IdentificationExcitationOptions& o) {
  double sweep_from = 0.0;  // fraction of the range
  if (o.settle_s > 0.0) {
    sweep_from = 0.5;
    SignalSpec hold;
    hold.kind = SignalKind::kSteps;
    hold.amplitude = span;
    hold.offset = range_min;
    hold.steps = {{sweep_from, o.settle_s}};
    builder.append("settle", hold);
  }
  if (o.precondition_s > 0.0) {
    // sweep_from -> range_max -> range_min at one rate; sampled, so a few samples per side.
    const double up = (1.0 - sweep_from) / (2.0 - sweep_from) * o.precondition_s;
    SignalSpec sweep;
    sweep.kind = SignalKind::kSamples;
    sweep.amplitude = span;
    sweep.offset = range_min;
    sweep.samples = {{0.0, sweep_from}, {up, 1.0}, {o.precondition_s, 0.0}};
    builder.append("precondition", sweep);
  }
}

// The major loop, the minor loops and the cycles at each rate frequency.
void append_loops(ExcitationBuilder& builder, double range_min, double span,
                  const IdentificationExcitationOptions& o) {
  builder.append("major_loop", cycles_from_bottom(range_min, span, o.major_loop_frequency_hz,
                                                  o.major_loop_cycles));

  if (o.minor_loops > 0) {
    SignalSpec minor;
    minor.kind = SignalKind::kDecayingSine;
    minor.rectified = true;  // |sin| makes two loops per sine period
    minor.amplitude = span;
    minor.offset = range_min;
    minor.frequency_hz = 0.5 * o.minor_loop_frequency_hz;
    minor.duration_s = o.minor_loops / o.minor_loop_frequency_hz;
    builder.append("minor_loops", minor);
  }

  for (std::size_t k = 0; k < o.rate_frequencies_hz.size(); ++k) {
    const double f = o.rate_frequencies_hz[k];
    builder.append("rate_" + compensation::significant(f, 6) + "hz",
                   cycles_from_bottom(range_min, o.rate_span_fraction * span, f, o.rate_cycles[k]));
  }
}

// Constant-rate ramps through the reversal points (none when no point moves the input).
void append_reversals(ExcitationBuilder& builder, double range_min, double span,
                      const IdentificationExcitationOptions& o) {
  if (o.reversal_points.empty()) return;
  SignalSpec reversals;
  reversals.kind = SignalKind::kSamples;
  reversals.amplitude = span;
  reversals.offset = range_min;
  double t = 0.0, previous = 0.0;
  reversals.samples.push_back({0.0, 0.0});
  for (const double point : o.reversal_points) {
    if (point == previous) continue;
    t += std::abs(point - previous) / o.reversal_rate_fraction_per_s;
    reversals.samples.push_back({t, point});
    previous = point;
  }
  if (reversals.samples.size() > 1) builder.append("reversals", reversals);
}

// One hold of hold_s at each hold level.
void append_holds(ExcitationBuilder& builder, double range_min, double span,
                  const IdentificationExcitationOptions& o) {
  for (std::size_t k = 0; k < o.hold_levels.size(); ++k) {
    SignalSpec hold;
    hold.kind = SignalKind::kSteps;
    hold.amplitude = span;
    hold.offset = range_min;
    hold.steps = {{o.hold_levels[k], o.hold_s}};
    builder.append("hold_" + std::to_string(k + 1), hold);
  }
}

}  // namespace

const ExcitationSegment* Excitation::find(const std::string& name) const noexcept {
  for (const auto& s : segments) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

Excitation identification_excitation(double range_min, double range_max, double dt_s,
                                     const IdentificationExcitationOptions& o) {
  validate(range_min, range_max, dt_s, o);
  const double span = range_max - range_min;
  ExcitationBuilder builder(range_min, range_max, dt_s);
  append_settle_and_sweep(builder, range_min, span, o);
  append_loops(builder, range_min, span, o);
  if (o.reversals_last) {
    append_holds(builder, range_min, span, o);
    append_reversals(builder, range_min, span, o);
  } else {
    append_reversals(builder, range_min, span, o);
    append_holds(builder, range_min, span, o);
  }
  return std::move(builder).finish();
}

}  // namespace hystbench::sim
