#include "hystbench/compensation/loop_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "details/validate.hpp"

namespace hystbench::compensation {

namespace {

constexpr double kPi = std::numbers::pi;

double to_db(double x) { return 20.0 * std::log10(x); }

// The point of a log-frequency interpolation from (f0, x0) to (f1, x1) where x crosses `level`.
double crossing_hz(double f0, double x0, double f1, double x1, double level) {
  const double w = (level - x0) / (x1 - x0);
  return std::exp(std::log(f0) + w * (std::log(f1) - std::log(f0)));
}

double wrap(double a) { return std::remainder(a, 2.0 * kPi); }

}  // namespace

bool meets(const LoopMargins& m, const LoopTargets& t) noexcept {
  return m.stable && m.gain_margin_db >= t.gain_margin_db &&
         m.phase_margin_deg >= t.phase_margin_deg && m.peak_sensitivity_db <= t.peak_sensitivity_db;
}

std::vector<std::complex<double>> loop_response(
    const MeasuredResponse& plant, const FeedbackController& c, double dt_s,
    std::vector<std::complex<double>>* controller_response) {
  std::vector<std::complex<double>> l(plant.size() + 1);
  if (controller_response != nullptr) controller_response->resize(l.size());
  for (std::size_t i = 0; i < l.size(); ++i) {
    // The loop's one-sample delay is z^-1 itself; at the Nyquist frequency it is -1 exactly.
    const bool nyquist = i == plant.size();
    const std::complex<double> zi =
        nyquist ? -1.0 : std::polar(1.0, -2.0 * kPi * plant.frequency_hz[i] * dt_s);
    const std::complex<double> ci = c.response_at(zi);
    if (controller_response != nullptr) (*controller_response)[i] = ci;
    l[i] = ci * zi * (nyquist ? plant.response.back() : plant.response[i]);
  }
  return l;
}

LoopMargins loop_margins(const MeasuredResponse& plant, const FeedbackController& c, double dt_s) {
  return loop_margins(plant, loop_response(plant, c, dt_s), c.law().pid.ki > 0.0, dt_s);
}

LoopMargins loop_margins(const MeasuredResponse& plant, std::span<const std::complex<double>> l,
                         bool integrator, double dt_s) {
  details::require(l.size() == plant.size() + 1,
                   "loop margins: one loop value per line and one at the Nyquist frequency");
  std::vector<double> f(plant.frequency_hz.begin(), plant.frequency_hz.end());
  f.push_back(0.5 / dt_s);
  LoopMargins m;
  const double half_power = 1.0 / std::sqrt(2.0);
  bool bandwidth_found = false, rejection_found = false, tenfold_found = false;
  double peak_s = 0.0, t_prev = 0.0, s_prev = 0.0, m_prev = 0.0;
  for (std::size_t i = 0; i < l.size(); ++i) {
    const double s = 1.0 / std::abs(1.0 + l[i]);
    if (s > peak_s) peak_s = s, m.peak_sensitivity_hz = f[i];
    const double magnitude = std::abs(l[i]);
    const double t = magnitude * s;
    if (!bandwidth_found && t < half_power) {
      bandwidth_found = true;
      m.bandwidth_hz = i == 0 ? 0.0 : crossing_hz(f[i - 1], t_prev, f[i], t, half_power);
    }
    if (!tenfold_found && s >= 0.1) {
      tenfold_found = true;
      m.tenfold_rejection_hz = i == 0 ? 0.0 : crossing_hz(f[i - 1], s_prev, f[i], s, 0.1);
    }
    if (!rejection_found && s >= half_power) {
      rejection_found = true;
      m.rejection_bandwidth_hz = i == 0 ? 0.0 : crossing_hz(f[i - 1], s_prev, f[i], s, half_power);
    }
    const double ma = m_prev, mb = std::log(magnitude);
    t_prev = t;
    s_prev = s;
    m_prev = mb;
    if (i == 0) continue;
    const std::complex<double> a = l[i - 1], b = l[i];
    // |L| crossing 1, in log magnitude.
    if ((ma >= 0.0) != (mb >= 0.0)) {
      const double w = ma / (ma - mb);
      const double fc = crossing_hz(f[i - 1], ma, f[i], mb, 0.0);
      // The phase along the chord's direction: interpolate the unwrapped step from a to b.
      const double phase = std::arg(a) + w * wrap(std::arg(b) - std::arg(a));
      const double pm = wrap(phase + kPi) * 180.0 / kPi;
      if (m.crossover_hz == 0.0) m.crossover_hz = fc;
      m.phase_margin_deg = std::min(m.phase_margin_deg, pm);
    }
    // L crossing the negative real axis.
    if ((a.imag() >= 0.0) != (b.imag() >= 0.0)) {
      const double w = a.imag() / (a.imag() - b.imag());
      const std::complex<double> x = a + w * (b - a);
      if (x.real() < 0.0) {
        const double gm = -to_db(-x.real());
        if (gm < m.gain_margin_db) {
          m.gain_margin_db = gm;
          m.gain_margin_hz = crossing_hz(f[i - 1], 0.0, f[i], 1.0, w);
        }
      }
    }
  }
  m.peak_sensitivity_db = to_db(peak_s);
  if (!bandwidth_found) m.bandwidth_hz = f.back();  // |T| above -3 dB up to the Nyquist frequency
  if (!rejection_found) m.rejection_bandwidth_hz = f.back();
  if (!tenfold_found) m.tenfold_rejection_hz = f.back();
  // The winding of 1 + L from the lowest line to the Nyquist frequency along the chords between
  // lines. A chord not through the origin turns by less than half a turn, the angle from its
  // start to its end. An integral loop starts at -90 degrees (1 + L ~ L ~ ki / (j w) times a
  // positive static gain), a loop without one at 0.
  const double start = integrator ? -kPi / 2.0 : 0.0;
  double phase = start + wrap(std::arg(1.0 + l[0]) - start);
  for (std::size_t i = 1; i < l.size(); ++i)
    phase += std::arg((1.0 + l[i]) * std::conj(1.0 + l[i - 1]));
  // Stable: the phase rises by 90 degrees (integrator) or not at all; each pair of closed-loop
  // poles outside the unit circle takes 180 degrees off.
  const double expected = integrator ? kPi / 2.0 : 0.0;
  m.unstable_poles = static_cast<int>(std::lround((start + expected - phase) / kPi));
  m.stable = m.unstable_poles == 0;
  return m;
}

}  // namespace hystbench::compensation
