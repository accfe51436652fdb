#include "hystbench/compensation/harmonic_resonator_design.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <optional>

#include "details/validate.hpp"
#include "hystbench/compensation/harmonic_resonators.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation {

namespace {

using Complex = std::complex<double>;
constexpr double kDeg = 180.0 / std::numbers::pi;

// r at f_hz, linear between the lines around it, held at its lowest line below it (a stage is
// flat there); nullopt above its top line.
std::optional<Complex> response_at(const MeasuredResponse& r, double f_hz) {
  const std::vector<double>& f = r.frequency_hz;
  if (f.empty() || f_hz > f.back()) return std::nullopt;
  if (f.size() == 1 || f_hz <= f.front()) return r.response.front();
  const auto above = std::upper_bound(f.begin(), f.end(), f_hz);
  const auto i = static_cast<std::size_t>(
      std::clamp<std::ptrdiff_t>(above - f.begin(), 1, static_cast<std::ptrdiff_t>(f.size()) - 1));
  const double w = (f_hz - f[i - 1]) / (f[i] - f[i - 1]);
  return (1.0 - w) * r.response[i - 1] + w * r.response[i];
}

// One response the design holds: as measured or with a mode moved, its gain times `gain`.
struct Variant {
  const MeasuredResponse* response = nullptr;
  double gain = 1.0;
  bool measured = false;  // as measured, its gain as measured
};

// What the resonators' output does to the error at f_hz, G = z^-1 P S, and the loop's |S|
// there, on variant v, the controller's response there being `controller` (the same for every
// variant): nullopt above its band.
struct AtFrequency {
  Complex g;
  double sensitivity = 0.0;
};
std::optional<AtFrequency> at_frequency(const Variant& v, Complex controller, double f_hz,
                                        double dt_s) {
  const std::optional<Complex> plant = response_at(*v.response, f_hz);
  if (!plant) return std::nullopt;
  const Complex delayed = v.gain * *plant * std::polar(1.0, -2.0 * std::numbers::pi * f_hz * dt_s);
  const Complex s = 1.0 / (1.0 + controller * delayed);
  return AtFrequency{delayed * s, std::abs(s)};
}

// Each kept resonator's settling (its adaptation): the fastest from settle_periods on at which
// |R G| stays within max_between on every variant between the kept harmonics and up to three
// fundamentals beyond the last (every line there, and each midpoint). Greedy: while the largest
// |R G| there is above it, the resonator that gives most of it there settles twice as slowly.
// Returns that largest |R G|; false in `met` where even max_settle_periods does not hold it.
double settle(std::vector<HarmonicResonator>& kept, std::vector<double>& periods,
              const std::vector<Variant>& variants, const FeedbackController& c,
              const HarmonicResonatorOptions& o, bool& met) {
  const double f = o.fundamental_hz;
  const double top = kept.back().frequency_hz + 3.0 * f;
  auto near_kept = [&](double x) {
    return std::any_of(kept.begin(), kept.end(), [&](const HarmonicResonator& h) {
      return std::abs(x - h.frequency_hz) < 0.25 * f;
    });
  };
  std::vector<double> grid;
  for (double x = 0.5 * f; x <= top; x += f) grid.push_back(x);
  for (const double x : variants.front().response->frequency_hz) {
    if (x >= 0.5 * f && x <= top) grid.push_back(x);
  }
  std::erase_if(grid, [&](double x) { return near_kept(x) || x >= 0.5 / o.dt_s; });
  // G on every variant at every point (0 above a variant's band), each resonator's R at unit mu.
  const std::size_t n = kept.size(), m = variants.size();
  std::vector<Complex> g(grid.size() * m), unit(grid.size() * n);
  for (std::size_t p = 0; p < grid.size(); ++p) {
    const Complex zi = std::polar(1.0, -2.0 * std::numbers::pi * grid[p] * o.dt_s);
    const Complex controller = c.response_at(zi);
    for (std::size_t v = 0; v < m; ++v) {
      const std::optional<AtFrequency> a = at_frequency(variants[v], controller, grid[p], o.dt_s);
      g[p * m + v] = a ? a->g : Complex{0.0, 0.0};
    }
    for (std::size_t k = 0; k < n; ++k) {
      HarmonicResonator r = kept[k];
      r.adaptation = 1.0;
      unit[p * n + k] = resonator_response(r, o.dt_s, zi);
    }
  }
  periods.assign(n, o.settle_periods);
  auto mu = [&](std::size_t k) { return std::min(0.5, 2.0 * f * o.dt_s / periods[k]); };
  for (;;) {
    double worst = 0.0;
    std::size_t at = 0;
    for (std::size_t p = 0; p < grid.size(); ++p) {
      Complex r{0.0, 0.0};
      for (std::size_t k = 0; k < n; ++k) r += mu(k) * unit[p * n + k];
      for (std::size_t v = 0; v < m; ++v) {
        if (const double x = std::abs(r * g[p * m + v]); x > worst) {
          worst = x;
          at = p;
        }
      }
    }
    met = worst <= o.max_between;
    std::size_t slowest = n;
    double most = 0.0;
    for (std::size_t k = 0; !met && k < n; ++k) {
      const double share = std::abs(mu(k) * unit[at * n + k]);
      if (periods[k] * 2.0 <= o.max_settle_periods && share > most) {
        most = share;
        slowest = k;
      }
    }
    if (met || slowest == n) {
      for (std::size_t k = 0; k < n; ++k) kept[k].adaptation = mu(k);
      return worst;
    }
    periods[slowest] *= 2.0;
  }
}

void validate_options(const HarmonicResonatorOptions& o) {
  details::require(std::isfinite(o.dt_s) && o.dt_s > 0.0, "harmonics: dt must be > 0");
  details::require(
      std::isfinite(o.fundamental_hz) && o.fundamental_hz > 0.0,
      "harmonics: the fundamental must be > 0 Hz, got " + significant(o.fundamental_hz, 6));
  details::require(o.max_frequency_fraction > 0.0 && o.max_frequency_fraction < 0.5,
                   "harmonics: max_frequency_fraction must be in (0, 0.5)");
  details::require(o.max_phase_spread_deg > 0.0 && o.max_phase_spread_deg < 90.0,
                   "harmonics: max_phase_spread_deg must be in (0, 90)");
  details::require(o.max_tick_phase_deg > 0.0 && o.max_tick_phase_deg < 180.0,
                   "harmonics: max_tick_phase_deg must be in (0, 180)");
  details::require(o.gain_uncertainty >= 0.0 && o.gain_uncertainty < 1.0,
                   "harmonics: gain_uncertainty must be in [0, 1)");
  details::require(o.mode_uncertainty >= 0.0 && o.mode_uncertainty < 1.0,
                   "harmonics: mode_uncertainty must be in [0, 1)");
  details::require(o.max_gain > 0.0 && o.settle_periods > 0.0 &&
                       o.max_settle_periods >= o.settle_periods && o.max_between > 0.0,
                   "harmonics: max_gain, settle_periods and max_between must be > 0, and "
                   "max_settle_periods at least settle_periods");
}

// The responses as measured and with each mode moved either way (those kept in `moved`), each
// with its gain as measured and changed either way; the ones as measured first.
std::vector<Variant> make_variants(std::span<const MeasuredResponse> responses,
                                   std::span<const MeasuredMode> modes,
                                   const HarmonicResonatorOptions& o,
                                   std::vector<MeasuredResponse>& moved) {
  for (const MeasuredResponse& r : responses) {
    for (const MeasuredMode& m : modes) {
      for (const double factor : {1.0 - o.mode_uncertainty, 1.0 + o.mode_uncertainty}) {
        if (o.mode_uncertainty > 0.0) moved.push_back(with_mode_moved(r, m, factor, o.dt_s));
      }
    }
  }
  std::vector<Variant> variants;
  for (const MeasuredResponse& r : responses) variants.push_back({&r, 1.0, true});
  for (const bool as_measured : {true, false}) {
    for (const MeasuredResponse& r :
         as_measured ? responses : std::span<const MeasuredResponse>(moved)) {
      for (const double gain : {1.0, 1.0 - o.gain_uncertainty, 1.0 + o.gain_uncertainty}) {
        if (!as_measured || gain != 1.0) variants.push_back({&r, gain, false});
      }
    }
  }
  return variants;
}

// Harmonic k judged on the variants; its resonator (adaptation still to settle) where kept.
HarmonicChoice judge_harmonic(std::size_t k, const std::vector<Variant>& variants,
                              const FeedbackController& c, const HarmonicResonatorOptions& o,
                              std::optional<HarmonicResonator>& resonator) {
  HarmonicChoice h;
  h.harmonic = k;
  h.frequency_hz = static_cast<double>(k) * o.fundamental_hz;
  Complex mean{0.0, 0.0};
  double largest = 0.0;
  std::vector<Complex> seen;
  const Complex controller = c.response(h.frequency_hz);
  for (const Variant& v : variants) {
    const std::optional<AtFrequency> a = at_frequency(v, controller, h.frequency_hz, o.dt_s);
    if (!a) break;
    seen.push_back(a->g);
    if (v.measured) {
      h.sensitivity = std::max(h.sensitivity, a->sensitivity);
      mean += a->g / std::abs(a->g);
      largest = std::max(largest, std::abs(a->g));
    }
  }
  if (seen.size() < variants.size()) {
    h.why = "above the measured responses' band";
    return h;
  }
  for (const Complex& g : seen) {
    h.phase_spread_deg = std::max(h.phase_spread_deg, std::abs(std::arg(g / mean)) * kDeg);
  }
  if (h.sensitivity <= o.min_sensitivity) {
    h.why = "the loop takes out more than " + significant(100.0 * (1.0 - o.min_sensitivity), 3) +
            " % there";
  } else if (!(h.phase_spread_deg <= o.max_phase_spread_deg)) {
    h.why = "its phase through the stage moves by " + significant(h.phase_spread_deg, 3) +
            " deg over the responses, their gain and their modes moved (at most " +
            significant(o.max_phase_spread_deg, 3) + ")";
  } else if (!(1.0 / largest <= o.max_gain)) {
    h.why = "the stage with its loop answers " + significant(largest, 3) +
            " there: too little to take it out";
  } else {
    h.kept = true;
    resonator = HarmonicResonator{h.frequency_hz, std::polar(1.0 / largest, -std::arg(mean)), 0.5};
  }
  return h;
}

}  // namespace

HarmonicResonatorDesign design_harmonic_resonators(std::span<const MeasuredResponse> responses,
                                                   const FeedbackLaw& law,
                                                   std::span<const MeasuredMode> modes,
                                                   const HarmonicResonatorOptions& o) {
  details::require(!responses.empty(), "harmonics: no measured response");
  validate_options(o);
  FeedbackLaw base = law;
  base.harmonics = {};
  const FeedbackController c(base, o.dt_s);
  std::vector<MeasuredResponse> moved;
  const std::vector<Variant> variants = make_variants(responses, modes, o, moved);
  HarmonicResonatorDesign d;
  d.spec.amplitude_limit =
      law.pid.output_max > 0.0 ? law.pid.output_max : std::numeric_limits<double>::infinity();
  // Above the first mode the loop leaves each harmonic whole (|S| near 1) and the feedforward
  // little there; resonators there only slow the lower ones, which must settle beside them.
  double first_mode_hz = std::numeric_limits<double>::infinity();
  for (const MeasuredMode& m : modes) first_mode_hz = std::min(first_mode_hz, m.frequency_hz);
  // A DAQ that answers a tick late now and then (a stale reading) turns a harmonic's phase by
  // 360 k f dt: on a 1 kHz loop 108 deg at 300 Hz, more than a resonator converges through.
  const double tick_hz = o.max_tick_phase_deg / 360.0 / o.dt_s;
  for (std::size_t k = 1; k <= o.max_harmonics; ++k) {
    const double f_k = static_cast<double>(k) * o.fundamental_hz;
    if (f_k > o.max_frequency_fraction / o.dt_s || f_k > first_mode_hz) break;
    if (k > o.min_harmonics && f_k > tick_hz) break;
    std::optional<HarmonicResonator> r;
    d.harmonics.push_back(judge_harmonic(k, variants, c, o, r));
    if (r) d.spec.resonators.push_back(*r);
  }
  // Where together they cannot settle within max_between, the highest harmonic goes first (the
  // lower ones carry more of a periodic error) until the rest can.
  std::vector<double> periods;
  bool met = false;
  while (!d.spec.resonators.empty()) {
    const double between = settle(d.spec.resonators, periods, variants, c, o, met);
    if (met) {
      d.between = between;
      break;
    }
    const double dropped = d.spec.resonators.back().frequency_hz;
    d.spec.resonators.pop_back();
    for (HarmonicChoice& h : d.harmonics) {
      if (!h.kept || h.frequency_hz != dropped) continue;
      h.kept = false;
      h.why = "with the resonators below it the loop between the harmonics would move by " +
              significant(between, 3) + " of 1 + L on a variant of the stage, even settling in " +
              significant(o.max_settle_periods, 3) + " periods (at most " +
              significant(o.max_between, 3) + ")";
    }
  }
  for (std::size_t i = 0, k = 0; i < d.harmonics.size() && met; ++i) {
    HarmonicChoice& h = d.harmonics[i];
    if (!h.kept) continue;
    h.settle_periods = periods[k++];
    d.settle_periods = std::max(d.settle_periods, h.settle_periods);
  }
  return d;
}

}  // namespace hystbench::compensation
