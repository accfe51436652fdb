#include "hystbench/sim/frequency_response_excitation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "hystbench/compensation/number_text.hpp"

namespace hystbench::sim {

namespace {

constexpr double kPeriodS = 0.1;
constexpr std::size_t kMinPeriod = 500;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("frequency response excitation: " + message);
}

void ramp(std::vector<double>& u, double a, double b, std::size_t n) {
  for (std::size_t k = 1; k <= n; ++k) {
    u.push_back(a + (b - a) * static_cast<double>(k) / static_cast<double>(n));
  }
}

// Log-spaced DFT lines from 1 to `top`, about `count` of them (every line where they crowd).
std::vector<std::size_t> log_lines(std::size_t top, std::size_t count) {
  std::vector<std::size_t> out;
  const double ratio = std::log(static_cast<double>(top)) / static_cast<double>(count - 1);
  for (std::size_t i = 0; i < count; ++i) {
    const auto line =
        static_cast<std::size_t>(std::lround(std::exp(ratio * static_cast<double>(i))));
    if (line >= 1 && line <= top && (out.empty() || line > out.back())) out.push_back(line);
  }
  return out;
}

// One period of the multisine with unit peak: Schroeder phases -pi k (k - 1) / K.
std::vector<double> multisine(std::size_t period, const std::vector<std::size_t>& lines) {
  std::vector<double> x(period, 0.0);
  const auto count = static_cast<double>(lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const double phase = -std::numbers::pi * static_cast<double>(i * (i + 1)) / count;
    const double w =
        2.0 * std::numbers::pi * static_cast<double>(lines[i]) / static_cast<double>(period);
    for (std::size_t k = 0; k < period; ++k) x[k] += std::cos(w * static_cast<double>(k) + phase);
  }
  double peak = 0.0;
  for (const double v : x) peak = std::max(peak, std::abs(v));
  for (double& v : x) v /= peak;
  return x;
}

// The moving part from x.u's end on: a move to the lower end, a hold, then ramps up and down
// with the sine on top, the first unaveraged.
void append_moving(FrequencyResponseExcitation& x, const FrequencyResponseExcitationOptions& o) {
  const double span = o.u_max - o.u_min, dt = 1.0 / o.rate_hz;
  const double lo = o.u_min + o.moving_from * span, hi = o.u_min + o.moving_to * span;
  // Whole cycles per ramp, more where the slew limit needs a slower ramp: its peak rate is the
  // ramp's and the sine's together, 1.5 x the ramp's.
  const double samples_per_cycle = 1.0 / o.moving_tone_fraction;
  const double slowest = 1.5 * (hi - lo) / o.slew_v_per_s / dt;  // samples, at least
  const auto cycles =
      std::max(o.moving_cycles, static_cast<std::size_t>(std::ceil(slowest / samples_per_cycle)));
  const auto n =
      static_cast<std::size_t>(std::lround(static_cast<double>(cycles) * samples_per_cycle));
  MovingExcitation& m = x.moving;
  m.tone_hz = static_cast<double>(cycles) * o.rate_hz / static_cast<double>(n);
  m.ramp_v_per_s = (hi - lo) / (static_cast<double>(n) * dt);
  m.amplitude_v = m.ramp_v_per_s / (4.0 * std::numbers::pi * m.tone_hz);
  const double move = std::max(o.move_s, std::abs(lo - x.u.back()) / o.slew_v_per_s);
  ramp(x.u, x.u.back(), lo,
       std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(move / dt))));
  x.u.insert(x.u.end(), static_cast<std::size_t>(std::ceil(o.hold_s / dt)), lo);
  for (std::size_t r = 0; r <= o.moving_ramps; ++r) {
    const bool rising = r % 2 == 0;
    if (r > 0) m.ramps.push_back({x.u.size(), n, rising});
    for (std::size_t k = 0; k < n; ++k) {
      const double along = static_cast<double>(k) / static_cast<double>(n);
      const double base = rising ? lo + (hi - lo) * along : hi - (hi - lo) * along;
      x.u.push_back(base + m.amplitude_v * std::sin(2.0 * std::numbers::pi * m.tone_hz *
                                                    static_cast<double>(k) * dt));
    }
  }
}

}  // namespace

FrequencyResponseExcitation make_frequency_response_excitation(
    const FrequencyResponseExcitationOptions& o) {
  require(std::isfinite(o.rate_hz) && o.rate_hz > 0.0, "rate_hz must be > 0");
  require(std::isfinite(o.u_min) && std::isfinite(o.u_max) && o.u_min < o.u_max,
          "u_min must be below u_max");
  require(std::isfinite(o.u_start), "u_start must be finite");
  require(o.slew_v_per_s > 0.0, "slew_v_per_s must be > 0");
  require(std::isfinite(o.precondition_s) && o.precondition_s >= 0.0,
          "precondition_s must be >= 0");
  require(!o.conditions.empty(), "no condition");
  require(o.periods >= 2, "periods must be >= 2 (their spread is the noise)");
  require(o.lines >= 4, "lines must be >= 4");
  require(o.top_fraction > 0.0 && o.top_fraction < 0.5, "top_fraction must be in (0, 0.5)");
  require(o.move_s >= 0.0 && o.hold_s >= 0.0, "move_s and hold_s must be >= 0");
  require(o.moving_tone_fraction >= 0.0 && o.moving_tone_fraction < 0.25,
          "moving_tone_fraction must be in [0, 0.25)");
  require(o.moving_tone_fraction == 0.0 ||
              (o.moving_cycles >= 2 && o.moving_ramps >= 2 && o.moving_ramps % 2 == 0 &&
               o.moving_from >= 0.0 && o.moving_from < o.moving_to && o.moving_to <= 1.0),
          "the moving part needs moving_cycles >= 2, an even moving_ramps >= 2 and 0 <= "
          "moving_from < moving_to <= 1");
  const double span = o.u_max - o.u_min, dt = 1.0 / o.rate_hz;
  FrequencyResponseExcitation x;
  x.period = std::max(kMinPeriod, static_cast<std::size_t>(std::lround(o.rate_hz * kPeriodS)));
  const auto top = static_cast<std::size_t>(o.top_fraction * static_cast<double>(x.period));
  x.lines = log_lines(top, o.lines);
  const std::vector<double> shape = multisine(x.period, x.lines);
  double steepest = 0.0;  // of the unit shape, per sample
  for (std::size_t k = 0; k < x.period; ++k) {
    steepest = std::max(steepest, std::abs(shape[(k + 1) % x.period] - shape[k]));
  }
  auto ticks = [&](double s) { return static_cast<std::size_t>(std::ceil(s / dt)); };
  // The sweep, each half at least as long as the slew limit needs.
  double u = std::clamp(o.u_start, o.u_min, o.u_max);
  if (o.precondition_s > 0.0) {
    const double half = std::max(o.precondition_s / 2.0, span / o.slew_v_per_s);
    ramp(x.u, u, o.u_max, std::max<std::size_t>(1, ticks(half * (o.u_max - u) / span)));
    ramp(x.u, o.u_max, o.u_min, std::max<std::size_t>(1, ticks(half)));
    u = o.u_min;
  }
  for (std::size_t c = 0; c < o.conditions.size(); ++c) {
    const ResponseCondition& rc = o.conditions[c];
    const std::string at = "conditions[" + std::to_string(c) + "]";
    require(rc.operating_fraction >= 0.0 && rc.operating_fraction <= 1.0,
            at + ".operating_fraction must be in [0, 1]");
    require(rc.amplitude_fraction > 0.0 && rc.amplitude_fraction <= 0.5,
            at + ".amplitude_fraction must be in (0, 0.5]");
    // Within the range around the operating point, and within the slew limit.
    const double centre = o.u_min + rc.operating_fraction * span;
    double amplitude = std::min({rc.amplitude_fraction * span, centre - o.u_min, o.u_max - centre});
    amplitude = std::min(amplitude, o.slew_v_per_s * dt / steepest);
    require(amplitude > 0.0, at + ": no room for the multisine at its operating point");
    const double move = std::max(o.move_s, std::abs(centre - u) / o.slew_v_per_s);
    ramp(x.u, u, centre + amplitude * shape[0], std::max<std::size_t>(1, ticks(move)));
    x.u.insert(x.u.end(), ticks(o.hold_s), centre + amplitude * shape[0]);
    for (std::size_t p = 0; p < o.transient_periods + o.periods; ++p) {
      if (p == o.transient_periods) {
        x.segments.push_back({x.u.size(), o.periods, centre, amplitude,
                              compensation::percent(rc.operating_fraction, 3) + " of the span, " +
                                  compensation::percent(amplitude / span, 3) + " peak"});
      }
      for (std::size_t k = 0; k < x.period; ++k) x.u.push_back(centre + amplitude * shape[k]);
    }
    u = x.u.back();
  }
  if (o.moving_tone_fraction > 0.0) append_moving(x, o);
  return x;
}

}  // namespace hystbench::sim
