// Candidate `dynamics`: a structural resonance after the hysteresis, seen as ringing after sharp
// reversals or steps and as a frequency-dependent gain and phase of the output against the
// baseline prediction. Extension: second-order dynamics (natural frequency, damping) found by
// a grid and line searches (Brent's) on the baseline prediction filtered through it, then every
// weight refitted jointly with the dynamics applied to the regressors.
// Statistic: the resonance peak of the measured response y/yhat: its largest gain over the
// informative bins (coherent, above the noise) between half and twice the fitted natural
// frequency, minus 1. A delay or a loop
// shape error shifts the phase but does not raise the gain; a lightly damped resonance does
// (1 / (2 zeta) at the natural frequency).
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include "details/line_minimum.hpp"
#include "diagnosis/details/candidates.hpp"

namespace hystbench::compensation::details {

namespace {

constexpr double kDynamicsThreshold = 0.15;
constexpr std::array<double, 4> kZetaGrid = {0.02, 0.07, 0.2, 0.5};
constexpr double kZetaMin = 0.003, kZetaMax = 1.0;
constexpr int kFrequenciesPerDecade = 8;
// A fitted resonance this far (ratio) in frequency, or in damping, from the measured response's
// peak was pulled off it: by a lag its phase stood in for. The peak's damping is read from its
// height, a coarse estimate: hence the wide ratio.
constexpr double kOffPeak = 1.15, kOffPeakDamping = 2.0;
// The variable projection's rounds end at a round that lowers the joint error by less than this
// fraction of it.
constexpr double kProjectionGain = 1e-4;
// The line searches' resolution in log frequency (0.1 %) and log damping (0.3 %), and their
// most evaluations.
constexpr double kLogFrequencyTolerance = 1e-3, kLogDampingTolerance = 3e-3;
constexpr int kMaxLineEvaluations = 16;

// Mean square errors of y ~ D_l[x] + b_l over the search rows (unit DC gain, as in the model),
// D_l the resonance at fn with damping zetas[l]: the L filters stepped side by side in one pass.
template <std::size_t L>
std::array<double, L> filtered_mses(const DiagnosisRecord& r, std::span<const double> x, double fn,
                                    const std::array<double, L>& zetas) {
  std::vector<SecondOrderDynamics> filters;
  filters.reserve(L);
  for (const double zeta : zetas) {
    filters.emplace_back(DynamicsParameters{fn, zeta}, r.dt);
    filters.back().reset(x[0]);
  }
  double n = 0, sy = 0, syy = 0;                // sums over the rows
  double sd[L] = {}, sdd[L] = {}, sdy[L] = {};  // and per filter
  double v[L];
  EveryNth search_rows(r.search_stride);
  for (std::size_t k = 0; k < r.n; ++k) {
    for (std::size_t l = 0; l < L; ++l) v[l] = filters[l].step(x[k]);
    if (!r.fit_row(k) || !search_rows.take()) continue;
    const double y = r.y[k];
    n += 1, sy += y, syy += y * y;
    for (std::size_t l = 0; l < L; ++l) sd[l] += v[l], sdd[l] += v[l] * v[l], sdy[l] += v[l] * y;
  }
  // sum (y - v - b)^2 with b the mean difference
  std::array<double, L> mse;
  for (std::size_t l = 0; l < L; ++l) {
    const double se = syy - 2.0 * sdy[l] + sdd[l];
    const double me = (sy - sd[l]) / n;
    mse[l] = std::max(0.0, se / n - me * me);
  }
  return mse;
}

double filtered_mse(const DiagnosisRecord& r, std::span<const double> x, double fn, double zeta) {
  return filtered_mses<1>(r, x, fn, {zeta})[0];
}

struct Resonance {
  double fn = 0.0, zeta = 0.0, mse = std::numeric_limits<double>::infinity();
};

// `best` moved to the minimum of mse(fn, best.zeta) over fn in [f_lo, f_hi], on log fn (its
// error best.mse known).
template <class Mse>
Resonance along_frequency(const Mse& mse, Resonance best, double f_lo, double f_hi) {
  const LineMinimum m = line_minimum([&](double l) { return mse(std::exp(l), best.zeta); },
                                     std::log(f_lo), std::log(f_hi), std::log(best.fn), best.mse,
                                     kLogFrequencyTolerance, kMaxLineEvaluations);
  return {std::exp(m.x), best.zeta, m.value};
}

// `best` moved to the minimum of mse(best.fn, zeta) over zeta in [z_lo, z_hi], on log zeta.
template <class Mse>
Resonance along_damping(const Mse& mse, Resonance best, double z_lo, double z_hi) {
  const LineMinimum m = line_minimum([&](double l) { return mse(best.fn, std::exp(l)); },
                                     std::log(z_lo), std::log(z_hi), std::log(best.zeta), best.mse,
                                     kLogDampingTolerance, kMaxLineEvaluations);
  return {best.fn, std::exp(m.x), m.value};
}

Resonance search(const DiagnosisRecord& r, std::span<const double> x, double f_lo, double f_hi,
                 std::optional<Resonance> start) {
  Resonance best;
  const double step = std::pow(10.0, 1.0 / kFrequenciesPerDecade);
  if (!start) {
    for (double fn = f_lo; fn <= f_hi; fn *= step) {
      const auto mses = filtered_mses(r, x, fn, kZetaGrid);
      for (std::size_t l = 0; l < kZetaGrid.size(); ++l) {
        if (mses[l] < best.mse) best = {fn, kZetaGrid[l], mses[l]};
      }
    }
  } else {
    best = *start;
  }
  // Refine: log frequency within one grid step, then log damping, then frequency again.
  const auto mse = [&](double fn, double zeta) { return filtered_mse(r, x, fn, zeta); };
  if (start) best.mse = mse(best.fn, best.zeta);  // start's error on another x
  for (int round = 0; round < 2; ++round) {
    best =
        along_frequency(mse, best, std::max(f_lo, best.fn / step), std::min(f_hi, best.fn * step));
    best = along_damping(mse, best, std::max(kZetaMin, best.zeta / 2.5),
                         std::min(kZetaMax, best.zeta * 2.5));
  }
  return best;
}

// Variable projection (DynamicsSearch): for a fixed (fn, zeta) every other unknown is linear, so
// the joint fit's error is a function of those two alone. It is minimised over log fn and log
// zeta by alternating line searches in shrinking brackets; this fits the resonance with the
// weights free, where the search above filters a fixed baseline prediction (whose weights have
// already absorbed part of the resonance, which biases fn low and zeta high). The rounds stop
// once one lowers the error by less than kProjectionGain of it: each evaluation is a joint fit
// over the whole record, and past that point the mode moves by less than the searches resolve.
// `start`'s error is evaluated unless it is known (finite).
Resonance project(const DynamicsSearch& j, Resonance start, double f_lo, double f_hi) {
  Resonance best = start;
  if (!std::isfinite(best.mse)) best.mse = j(best.fn, best.zeta);
  double f_span = 1.15, z_span = 2.0;  // bracket half-widths (factors)
  for (int round = 0; round < 4; ++round) {
    const double before = best.mse;
    best = along_frequency(j, best, std::max(f_lo, best.fn / f_span),
                           std::min(f_hi, best.fn * f_span));
    best = along_damping(j, best, std::max(kZetaMin, best.zeta / z_span),
                         std::min(kZetaMax, best.zeta * z_span));
    if (before - best.mse <= kProjectionGain * before) break;
    f_span = std::sqrt(f_span), z_span = std::sqrt(z_span);
  }
  return best;
}

// The resonance the measured response shows: its largest informative gain above f_lo, damping
// from the peak height (1 / (2 zeta) at the natural frequency of a lightly damped mode).
std::optional<Resonance> spectral_peak(const FrequencyResponse& fr, double f_lo, double f_hi) {
  std::optional<Resonance> peak;
  double gain = 1.0;
  for (std::size_t i = 0; i < fr.frequency_hz.size(); ++i) {
    const double f = fr.frequency_hz[i];
    if (f < f_lo || f > f_hi || !fr.informative[i] || fr.gain[i] <= gain) continue;
    gain = fr.gain[i];
    peak = Resonance{f, std::clamp(0.5 / gain, 0.01, 0.5), 0.0};
  }
  return peak;
}

// A fitted mode within kOffPeak in frequency and kOffPeakDamping in damping of the measured peak.
bool on_peak(const DynamicsParameters& mode, const Resonance& peak) {
  return std::abs(std::log(mode.natural_frequency_hz / peak.fn)) < std::log(kOffPeak) &&
         std::abs(std::log(mode.damping_ratio / peak.zeta)) < std::log(kOffPeakDamping);
}

// `mode` with the frequency and damping of `found` (its feedforward roll-off kept).
DynamicsParameters moved_to(DynamicsParameters mode, const Resonance& found) {
  mode.natural_frequency_hz = found.fn;
  mode.damping_ratio = found.zeta;
  return mode;
}

// The hysteresis-and-creep output of a model (its dynamics removed), delay kept.
std::vector<double> static_prediction(const ExtensionFit& f, const DiagnosisRecord& r) {
  ActuatorModel m(f.model);
  m.set_dynamics(std::nullopt);
  std::vector<double> x = m.simulate(r.u, r.dt);
  for (std::size_t k = 0; k < f.drift.size(); ++k) x[k] += f.drift[k];
  return x;
}

// The joint projection from the better (by the joint objective) of `estimate` and the measured
// response's `peak`.
Resonance project_from(const DynamicsSearch& joint, Resonance estimate,
                       const std::optional<Resonance>& peak, double f_lo, double f_hi) {
  estimate.mse = joint(estimate.fn, estimate.zeta);
  if (peak) {
    const double mse = joint(peak->fn, peak->zeta);
    if (mse < estimate.mse) estimate = {peak->fn, peak->zeta, mse};
  }
  return project(joint, estimate, f_lo, f_hi);
}

// The band the resonance is searched in: up to 0.45 fs, from 20 periods over the record.
std::pair<double, double> resonance_band(const DiagnosisRecord& r) {
  const double f_hi = 0.45 / r.dt;
  return {std::min(0.1 * f_hi, std::max(0.5, 20.0 / r.duration())), f_hi};
}

}  // namespace

std::optional<DynamicsParameters> refit_resonance(const DiagnosisRecord& r,
                                                  const ExtensionSpec& spec,
                                                  const FrequencyResponse& response) {
  const auto [f_lo, f_hi] = resonance_band(r);
  const auto peak = spectral_peak(response, f_lo, f_hi);
  if (!peak || on_peak(*spec.dynamics, *peak)) return std::nullopt;
  const DynamicsSearch joint(r, spec);
  const Resonance best = project_from(
      joint, {spec.dynamics->natural_frequency_hz, spec.dynamics->damping_ratio}, peak, f_lo, f_hi);
  return moved_to(*spec.dynamics, best);
}

std::optional<DynamicsParameters> project_resonance(const DiagnosisRecord& r,
                                                    const ExtensionSpec& spec,
                                                    const FrequencyResponse& response) {
  const auto [f_lo, f_hi] = resonance_band(r);
  const auto peak = spectral_peak(response, f_lo, f_hi);
  if (!peak || !on_peak(*spec.dynamics, *peak)) return std::nullopt;
  if (alternates(spec)) return std::nullopt;
  const DynamicsSearch joint(r, spec);
  const Resonance best = project(
      joint, {spec.dynamics->natural_frequency_hz, spec.dynamics->damping_ratio}, f_lo, f_hi);
  return moved_to(*spec.dynamics, best);
}

CandidateOutcome test_dynamics(const CandidateContext& c) {
  CandidateOutcome out;
  const DiagnosisRecord& r = c.record;
  const auto [f_lo, f_hi] = resonance_band(r);

  std::vector<double> x = static_prediction(c.base_fit, r);
  Resonance res = search(r, x, f_lo, f_hi, std::nullopt);
  // Every fit below differs from the base only in its dynamics: the design is stepped once.
  const DynamicsSearch joint(r, c.base);
  const DesignRows& rows = joint.rows();
  ExtensionSpec spec = c.base;
  spec.dynamics = DynamicsParameters{res.fn, res.zeta};
  ExtensionFit fit = fit_extension(r, spec, FitRows::kAll, true, &rows);
  // Once more from the jointly refitted hysteresis.
  x = static_prediction(fit, r);
  const Resonance again = search(r, x, f_lo, f_hi, res);
  ExtensionSpec spec2 = c.base;
  spec2.dynamics = DynamicsParameters{again.fn, again.zeta};
  ExtensionFit fit2 = fit_extension(r, spec2, FitRows::kAll, true, &rows);
  if (fit2.fit.rmse < fit.fit.rmse) fit = std::move(fit2), res = again;
  // Then jointly with the weights, from the better of that estimate and the spectral peak.
  const Resonance projected =
      project_from(joint, res, spectral_peak(c.response, f_lo, f_hi), f_lo, f_hi);
  ExtensionSpec spec3 = c.base;
  spec3.dynamics = DynamicsParameters{projected.fn, projected.zeta};
  ExtensionFit fit3 = fit_extension(r, spec3, FitRows::kAll, true, &rows);
  if (fit3.fit.rmse < fit.fit.rmse) fit = std::move(fit3), res = projected;
  out.fit = std::move(fit);
  out.extension =
      "second-order dynamics: natural frequency " + num(res.fn) + " Hz, damping " + num(res.zeta);

  // Evidence from the measured frequency response around the fitted resonance.
  const FrequencyResponse& fr = c.response;
  double worst = 0.0, at = 0.0, gain = 1.0, phase = 0.0;
  for (std::size_t i = 0; i < fr.frequency_hz.size(); ++i) {
    const double f = fr.frequency_hz[i];
    if (f < 0.5 * res.fn || f > 2.0 * res.fn || !fr.informative[i]) continue;
    if (fr.gain[i] - 1.0 > worst) {
      worst = fr.gain[i] - 1.0, at = f, gain = fr.gain[i], phase = fr.phase_rad[i];
    }
  }
  out.statistic = worst;
  out.threshold = kDynamicsThreshold;
  out.evidence =
      worst > 0.0 ? "the measured/predicted response peaks at gain " + num(gain) + " near " +
                        num(at) + " Hz (phase " + num(phase * 180.0 / std::numbers::pi) +
                        " deg); " + std::to_string(c.events.steps) + " steps and " +
                        std::to_string(c.events.reversals) + " reversals excite it"
                  : "no resonance peak in the coherent measured response above the noise between " +
                        num(0.5 * res.fn) + " and " + num(2.0 * res.fn) + " Hz";
  return out;
}

}  // namespace hystbench::compensation::details
