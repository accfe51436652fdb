#include "hystbench/sim/signal_generator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

namespace hystbench::sim {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

constexpr std::array<std::pair<SignalKind, std::string_view>, 9> kKindNames{{
    {SignalKind::kSine, "sine"},
    {SignalKind::kDecayingSine, "decaying_sine"},
    {SignalKind::kTriangle, "triangle"},
    {SignalKind::kSawtooth, "sawtooth"},
    {SignalKind::kStep, "step"},
    {SignalKind::kSteps, "steps"},
    {SignalKind::kMultiFrequency, "multi_frequency"},
    {SignalKind::kChirp, "chirp"},
    {SignalKind::kSamples, "csv"},
}};

void require_signal(bool ok, const std::string& field, const std::string& what) {
  if (!ok) throw std::invalid_argument("signal." + field + ": " + what);
}

void require_positive_signal(double value, const std::string& field) {
  require_signal(std::isfinite(value) && value > 0.0, field, "must be > 0");
}

double fractional_part(double x) noexcept { return x - std::floor(x); }

/// offset + amplitude * shape(t): the part every kind shares.
class ShapedSignal : public SignalGenerator {
 public:
  explicit ShapedSignal(const SignalSpec& spec, double duration_s)
      : offset_(spec.offset), amplitude_(spec.amplitude), duration_s_(duration_s) {}
  double value(double t_s) const noexcept final { return offset_ + amplitude_ * shape(t_s); }
  double duration_s() const noexcept final { return duration_s_; }

 protected:
  virtual double shape(double t_s) const noexcept = 0;
  /// t clamped to [0, duration]: finite signals hold their ends.
  double clamp_time(double t_s) const noexcept { return std::clamp(t_s, 0.0, duration_s_); }

 private:
  double offset_;
  double amplitude_;
  double duration_s_;
};

/// Sine, triangle, sawtooth and step: a shape of the cycle fraction x = f t + phase / 2 pi.
class PeriodicSignal final : public ShapedSignal {
 public:
  explicit PeriodicSignal(const SignalSpec& spec)
      : ShapedSignal(spec, spec.duration_s),
        kind_(spec.kind),
        frequency_hz_(spec.frequency_hz),
        cycle_offset_(spec.phase_rad / kTwoPi),
        rise_cycles_(std::min(spec.rise_s * spec.frequency_hz, 0.25)) {}

 private:
  double shape(double t_s) const noexcept override {
    const double x = frequency_hz_ * t_s + cycle_offset_;
    switch (kind_) {
      case SignalKind::kTriangle:
        return 1.0 - 4.0 * std::abs(fractional_part(x + 0.25) - 0.5);
      case SignalKind::kSawtooth:
        return 2.0 * fractional_part(x + 0.5) - 1.0;
      case SignalKind::kStep: {
        // Up at cycle 0, down at 0.5, each along a minimum-jerk move of rise_cycles_.
        const double c = fractional_part(x);
        const double into = c < 0.5 ? c : c - 0.5;
        const double to = c < 0.5 ? 1.0 : -1.0;
        if (into >= rise_cycles_) return to;
        const double r = into / rise_cycles_;
        return -to + 2.0 * to * r * r * r * (10.0 - 15.0 * r + 6.0 * r * r);
      }
      default:
        return std::sin(kTwoPi * x);
    }
  }

  SignalKind kind_;
  double frequency_hz_;
  double cycle_offset_;
  double rise_cycles_;  // step: its edges' move, in cycles
};

class DecayingSineSignal final : public ShapedSignal {
 public:
  explicit DecayingSineSignal(const SignalSpec& spec)
      : ShapedSignal(spec, spec.duration_s),
        frequency_hz_(spec.frequency_hz),
        phase_rad_(spec.phase_rad),
        rectified_(spec.rectified) {}

 private:
  double shape(double t_s) const noexcept override {
    const double t = clamp_time(t_s);
    const double s = std::sin(kTwoPi * frequency_hz_ * t + phase_rad_);
    return (1.0 - t / duration_s()) * (rectified_ ? std::abs(s) : s);
  }

  double frequency_hz_;
  double phase_rad_;
  bool rectified_;
};

class ChirpSignal final : public ShapedSignal {
 public:
  explicit ChirpSignal(const SignalSpec& spec)
      : ShapedSignal(spec, spec.duration_s),
        f0_hz_(spec.frequency_hz),
        f1_hz_(spec.end_frequency_hz),
        phase_rad_(spec.phase_rad) {}

 private:
  double shape(double t_s) const noexcept override {
    const double sweep_s = duration_s();
    const double t = std::clamp(t_s, 0.0, sweep_s);
    // Phase is the integral of f(t) = f0 + (f1 - f0) t / T, continued at f1 after T.
    double cycles = f0_hz_ * t + 0.5 * (f1_hz_ - f0_hz_) * t * t / sweep_s;
    if (t_s > sweep_s) cycles += f1_hz_ * (t_s - sweep_s);
    return std::sin(kTwoPi * cycles + phase_rad_);
  }

  double f0_hz_;
  double f1_hz_;
  double phase_rad_;
};

class MultiFrequencySignal final : public ShapedSignal {
 public:
  explicit MultiFrequencySignal(const SignalSpec& spec)
      : ShapedSignal(spec, spec.duration_s),
        frequencies_hz_(spec.component_frequencies_hz),
        modulation_hz_(spec.modulation_frequency_hz) {}

 private:
  double shape(double t_s) const noexcept override {
    const double count = static_cast<double>(frequencies_hz_.size());
    double sum = 0.0;
    for (std::size_t k = 0; k < frequencies_hz_.size(); ++k) {
      const double envelope =
          0.5 * (1.0 - std::cos(kTwoPi * (modulation_hz_ * t_s + static_cast<double>(k) / count)));
      sum += envelope * std::sin(kTwoPi * frequencies_hz_[k] * t_s);
    }
    return sum / count;
  }

  std::vector<double> frequencies_hz_;
  double modulation_hz_;
};

double total_hold_s(const std::vector<StepLevel>& steps) {
  double total = 0.0;
  for (const auto& s : steps) total += s.hold_s;
  return total;
}

class StepsSignal final : public ShapedSignal {
 public:
  explicit StepsSignal(const SignalSpec& spec)
      : ShapedSignal(spec, spec.repeat_steps ? kInfiniteDuration : total_hold_s(spec.steps)),
        sequence_s_(total_hold_s(spec.steps)),
        repeat_(spec.repeat_steps) {
    double end = 0.0;
    for (const auto& s : spec.steps) {
      end += s.hold_s;
      end_times_s_.push_back(end);
      levels_.push_back(s.level);
    }
  }

 private:
  double shape(double t_s) const noexcept override {
    double t = std::max(t_s, 0.0);
    if (repeat_) t = std::fmod(t, sequence_s_);
    const auto it = std::upper_bound(end_times_s_.begin(), end_times_s_.end(), t);
    if (it == end_times_s_.end()) return levels_.back();
    return levels_[static_cast<std::size_t>(it - end_times_s_.begin())];
  }

  std::vector<double> end_times_s_;
  std::vector<double> levels_;
  double sequence_s_;
  bool repeat_;
};

class SamplesSignal final : public ShapedSignal {
 public:
  explicit SamplesSignal(const SignalSpec& spec)
      : ShapedSignal(spec, spec.samples.back().t_s), samples_(spec.samples) {}

 private:
  double shape(double t_s) const noexcept override {
    if (t_s <= samples_.front().t_s) return samples_.front().value;
    if (t_s >= samples_.back().t_s) return samples_.back().value;
    const auto after = std::upper_bound(samples_.begin(), samples_.end(), t_s,
                                        [](double t, const TimedSample& s) { return t < s.t_s; });
    const auto before = after - 1;
    const double f = (t_s - before->t_s) / (after->t_s - before->t_s);
    return before->value + f * (after->value - before->value);
  }

  std::vector<TimedSample> samples_;
};

class UniformSignal final : public SignalGenerator {
 public:
  UniformSignal(std::vector<double> values, double dt_s)
      : values_(std::move(values)), dt_s_(dt_s) {}
  double value(double t_s) const noexcept override {
    const double x = t_s / dt_s_;
    if (!(x > 0.0)) return values_.front();  // before the start, and NaN
    const double last = static_cast<double>(values_.size() - 1);
    if (x >= last) return values_.back();
    const auto k = static_cast<std::size_t>(x);
    const double f = x - static_cast<double>(k);
    return values_[k] + f * (values_[k + 1] - values_[k]);
  }
  double duration_s() const noexcept override {
    return static_cast<double>(values_.size() - 1) * dt_s_;
  }

 private:
  std::vector<double> values_;
  double dt_s_;
};

void validate(const SignalSpec& spec) {
  require_signal(std::isfinite(spec.amplitude), "amplitude", "must be a finite number");
  require_signal(std::isfinite(spec.offset), "offset", "must be a finite number");
  require_signal(std::isfinite(spec.phase_rad), "phase_rad", "must be a finite number");
  require_signal(std::isfinite(spec.rise_s) && spec.rise_s >= 0.0, "rise_s", "must be >= 0");
  const std::string kind(to_string(spec.kind));
  switch (spec.kind) {
    case SignalKind::kSine:
    case SignalKind::kTriangle:
    case SignalKind::kSawtooth:
    case SignalKind::kStep:
    case SignalKind::kMultiFrequency:
      require_signal(spec.duration_s > 0.0, "duration_s", "must be > 0 (infinite allowed)");
      break;
    case SignalKind::kDecayingSine:
    case SignalKind::kChirp:
      require_positive_signal(spec.duration_s, "duration_s");
      break;
    case SignalKind::kSteps:
    case SignalKind::kSamples:
      break;
  }
  switch (spec.kind) {
    case SignalKind::kChirp:
      require_positive_signal(spec.end_frequency_hz, "end_frequency_hz");
      [[fallthrough]];
    case SignalKind::kSine:
    case SignalKind::kTriangle:
    case SignalKind::kSawtooth:
    case SignalKind::kStep:
    case SignalKind::kDecayingSine:
      require_positive_signal(spec.frequency_hz, "frequency_hz");
      break;
    case SignalKind::kMultiFrequency:
      require_signal(!spec.component_frequencies_hz.empty(), "component_frequencies_hz",
                     "must not be empty");
      for (std::size_t k = 0; k < spec.component_frequencies_hz.size(); ++k) {
        require_positive_signal(spec.component_frequencies_hz[k],
                                "component_frequencies_hz[" + std::to_string(k) + "]");
      }
      require_positive_signal(spec.modulation_frequency_hz, "modulation_frequency_hz");
      break;
    case SignalKind::kSteps:
      require_signal(!spec.steps.empty(), "steps", "must not be empty for kind " + kind);
      for (std::size_t k = 0; k < spec.steps.size(); ++k) {
        const std::string field = "steps[" + std::to_string(k) + "]";
        require_signal(std::isfinite(spec.steps[k].level), field + ".level",
                       "must be a finite number");
        require_positive_signal(spec.steps[k].hold_s, field + ".hold_s");
      }
      break;
    case SignalKind::kSamples:
      require_signal(!spec.samples.empty(), "samples", "must not be empty for kind " + kind);
      for (std::size_t k = 0; k < spec.samples.size(); ++k) {
        const std::string field = "samples[" + std::to_string(k) + "]";
        require_signal(std::isfinite(spec.samples[k].t_s) && std::isfinite(spec.samples[k].value),
                       field, "time and value must be finite numbers");
        require_signal(k == 0 || spec.samples[k].t_s > spec.samples[k - 1].t_s, field + ".t_s",
                       "must be greater than the previous sample's (strictly increasing)");
      }
      break;
  }
}

}  // namespace

std::string_view to_string(SignalKind kind) noexcept {
  for (const auto& [k, name] : kKindNames) {
    if (k == kind) return name;
  }
  return "unknown";
}

SignalKind signal_kind_from_string(std::string_view name) {
  std::string valid;
  for (const auto& [kind, kind_name] : kKindNames) {
    if (kind_name == name) return kind;
    valid += (valid.empty() ? "" : ", ") + std::string(kind_name);
  }
  throw std::invalid_argument("unknown signal kind \"" + std::string(name) + "\" (valid: " + valid +
                              ")");
}

std::unique_ptr<SignalGenerator> make_signal_generator(const SignalSpec& spec) {
  validate(spec);
  switch (spec.kind) {
    case SignalKind::kSine:
    case SignalKind::kTriangle:
    case SignalKind::kSawtooth:
    case SignalKind::kStep:
      return std::make_unique<PeriodicSignal>(spec);
    case SignalKind::kDecayingSine:
      return std::make_unique<DecayingSineSignal>(spec);
    case SignalKind::kSteps:
      return std::make_unique<StepsSignal>(spec);
    case SignalKind::kMultiFrequency:
      return std::make_unique<MultiFrequencySignal>(spec);
    case SignalKind::kChirp:
      return std::make_unique<ChirpSignal>(spec);
    case SignalKind::kSamples:
      return std::make_unique<SamplesSignal>(spec);
  }
  throw std::invalid_argument("signal.kind: unknown value");
}

std::unique_ptr<SignalGenerator> make_uniform_signal(std::vector<double> values, double dt_s) {
  require_signal(std::isfinite(dt_s) && dt_s > 0.0, "dt_s", "must be > 0");
  require_signal(!values.empty(), "values", "must not be empty");
  for (std::size_t k = 0; k < values.size(); ++k) {
    require_signal(std::isfinite(values[k]), "values[" + std::to_string(k) + "]",
                   "must be a finite number");
  }
  return std::make_unique<UniformSignal>(std::move(values), dt_s);
}

std::vector<double> sample_signal(const SignalGenerator& generator, double dt_s,
                                  double duration_s) {
  if (!(std::isfinite(dt_s) && dt_s > 0.0)) throw std::invalid_argument("dt_s: must be > 0");
  const double duration = duration_s < 0.0 ? generator.duration_s() : duration_s;
  if (!std::isfinite(duration)) {
    throw std::invalid_argument("duration_s: must be finite to sample a signal");
  }
  const auto n = static_cast<std::size_t>(std::llround(duration / dt_s));
  std::vector<double> values(n);
  for (std::size_t k = 0; k < n; ++k) values[k] = generator.value(static_cast<double>(k) * dt_s);
  return values;
}

}  // namespace hystbench::sim
