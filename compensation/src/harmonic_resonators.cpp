#include "hystbench/compensation/harmonic_resonators.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "details/validate.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation {

namespace {
// The phasors are renormalised this often: their rounding would otherwise drift |e^{j w n}|.
constexpr std::size_t kRenormaliseTicks = 1024;
}  // namespace

std::complex<double> resonator_response(const HarmonicResonator& r, double dt_s,
                                        std::complex<double> zi) noexcept {
  const std::complex<double> q = std::polar(1.0, 2.0 * std::numbers::pi * r.frequency_hz * dt_s);
  return 0.5 * r.adaptation *
         (r.gain / (1.0 - q * zi) + std::conj(r.gain) / (1.0 - std::conj(q) * zi));
}

HarmonicResonators::HarmonicResonators(const HarmonicResonatorsSpec& spec, double dt_s)
    : spec_(spec), dt_(dt_s) {
  details::require(std::isfinite(dt_s) && dt_s > 0.0, "harmonics: dt must be > 0");
  if (spec.empty()) return;
  details::require(spec.amplitude_limit > 0.0, "harmonics.amplitude_limit must be > 0");
  for (std::size_t k = 0; k < spec.resonators.size(); ++k) {
    const HarmonicResonator& r = spec.resonators[k];
    const std::string field = "harmonics.resonators[" + std::to_string(k) + "]";
    details::require(
        std::isfinite(r.frequency_hz) && r.frequency_hz > 0.0 && r.frequency_hz < 0.5 / dt_s,
        field + ".frequency_hz must be in (0, " + significant(0.5 / dt_s, 6) + ") Hz, got " +
            significant(r.frequency_hz, 6));
    details::require(
        std::isfinite(r.gain.real()) && std::isfinite(r.gain.imag()) && std::abs(r.gain) > 0.0,
        field + ".gain must be finite and nonzero");
    details::require(
        std::isfinite(r.adaptation) && r.adaptation > 0.0 && r.adaptation <= 0.5,
        field + ".adaptation must be in (0, 0.5], got " + significant(r.adaptation, 6));
    states_.push_back(
        {std::polar(1.0, 2.0 * std::numbers::pi * r.frequency_hz * dt_s), {1.0, 0.0}, {0.0, 0.0}});
  }
}

double HarmonicResonators::step(double error) noexcept {
  if (!std::isfinite(error)) return out_;
  const bool renormalise = ++ticks_ % kRenormaliseTicks == 0;
  double out = 0.0;
  for (std::size_t k = 0; k < states_.size(); ++k) {
    State& s = states_[k];
    const HarmonicResonator& r = spec_.resonators[k];
    if (!frozen_) {
      s.amplitude += r.adaptation * error * std::conj(s.phase);
      const double held = std::abs(r.gain * s.amplitude);
      if (held > spec_.amplitude_limit) s.amplitude *= spec_.amplitude_limit / held;
    }
    out += (r.gain * s.amplitude * s.phase).real();
    s.phase *= s.step;
    if (renormalise) s.phase /= std::abs(s.phase);
  }
  out_ = out;
  return out_;
}

void HarmonicResonators::reset() noexcept {
  for (State& s : states_) {
    s.phase = {1.0, 0.0};
    s.amplitude = {0.0, 0.0};
  }
  out_ = 0.0;
  ticks_ = 0;
}

std::complex<double> HarmonicResonators::response_at(std::complex<double> zi) const noexcept {
  std::complex<double> sum{0.0, 0.0};
  for (const HarmonicResonator& r : spec_.resonators) sum += resonator_response(r, dt_, zi);
  return sum;
}

}  // namespace hystbench::compensation
