#include "hystbench/compensation/inverse_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "details/validate.hpp"
#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"

namespace hystbench::compensation {

namespace {
// The rate-dependent inverse's rate prediction is low-passed over at least this many samples.
constexpr double kMinRatePredictionSamples = 5.0;
// Signed law falling with the rate, step(): per-tick drive change at most this many times the
// rate-free inverse's, and at least this fraction of max_rate per tick.
constexpr double kSignedStepFactor = 2.0;
constexpr double kSignedSettleRateFraction = 0.01;
// Thresholds law: inverted at the drive's own rate while beta a / dt stays below this (the
// output then grows with the drive by at least 1 - this per unit on every branch).
constexpr double kOwnRateMonotoneMargin = 0.8;

// Thresholds law: on a branch the output is u - r_i - widening(rate(u)) per play, and the rate
// moves with the drive by a / dt per unit of it. A linear widening beta * rate keeps the output
// growing with the drive at its own rate while beta a / dt stays below the margin; a widening
// that grows as a power p < 1 of the rate grows without bound near rate 0, so never.
bool thresholds_grow_at_own_rate(const ThresholdsRateLaw& law, double dt) {
  const double a = RateEstimator(law.rate_filter_s, dt).coefficient();
  return law.exponent == 1.0 && law.threshold_rate_s * a / dt < kOwnRateMonotoneMargin;
}

// The sample period the hysteresis reads its rate at [s]: the rate-dependent PI keeps its own
// (set when it is built), every other model the actuator model's.
double rate_sample_period(const ActuatorModel& model) {
  const auto* rpi = dynamic_cast<const RateDependentPiModel*>(&model.hysteresis());
  return rpi != nullptr ? rpi->sample_period() : model.sample_period();
}

// The model with its hysteresis's rate law taken out (creep and the rate's sample period kept),
// over [input_min, input_max], at rest at u0: the drive it inverts to predicts the rate of the
// full model's drive.
ActuatorModel rate_free_model(const ActuatorModel& model, double input_min, double input_max,
                              double u0) {
  ActuatorModel rate_free(model.hysteresis().rate_free_part());
  rate_free.set_creep(model.creep());
  rate_free.input_min = input_min;
  rate_free.input_max = input_max;
  rate_free.configure(rate_sample_period(model));
  rate_free.reset(u0);
  return rate_free;
}
}  // namespace

// ---------------------------------------------------------------- PiInverse

PiInverse::PiInverse(const PiModel& model, InputRange range)
    : model_(model.parameters()),
      inv_(compensation::inverse_parameters(model.parameters())),
      reach_(model, range) {
  inv_.set_state(inverse_state(model_, model.state()));
}

double PiInverse::step(double y_ref) noexcept {
  return reach_.step(y_ref, [this](double y) { return inv_.step(y - model_.offset); });
}

void PiInverse::reset(double u0) noexcept {
  // Model plays all at u0 => inverse plays p'_i = W_n * u0 (see inverse_state()).
  double total = 0.0;
  for (const double w : model_.weights) total += w;
  inv_.reset(total * u0);
  reach_.reset(u0);
}

std::unique_ptr<InverseModel> PiInverse::clone() const {
  return std::make_unique<PiInverse>(*this);
}

// ---------------------------------------------------------------- ModifiedPiInverse

ModifiedPiInverse::ModifiedPiInverse(const ModifiedPiModel& model, InputRange range)
    : center_(model.parameters().center),
      dz_inv_(model.dead_zone_part().inverse()),
      pi_inv_(model.play_part()),
      reach_(model, range) {}

double ModifiedPiInverse::step(double y_ref) noexcept {
  return reach_.step(
      y_ref, [this](double y) { return pi_inv_.step(center_ + dz_inv_.apply(y - center_)); });
}

void ModifiedPiInverse::reset(double u0) noexcept {
  pi_inv_.reset(u0);
  reach_.reset(u0);
}

std::unique_ptr<InverseModel> ModifiedPiInverse::clone() const {
  return std::make_unique<ModifiedPiInverse>(*this);
}

// ---------------------------------------------------------------- NumericInverse

NumericInverse::NumericInverse(const ActuatorModel& model, Options options)
    : model_(model), opt_(options) {
  details::require(model_.valid(), "numeric inverse needs a model");
  if (!(opt_.input_min < opt_.input_max)) {
    opt_.input_min = model_.input_min;
    opt_.input_max = model_.input_max;
  }
  details::require(opt_.input_min < opt_.input_max,
                   "numeric inverse needs an input range (input_min < input_max)");
  const Invertibility inv = model_.hysteresis().invertibility();
  if (!inv.invertible) throw NotInvertibleError(inv);
  // Static model only: dropping delay and dynamics keeps the hysteresis and creep state.
  model_.set_delay(0.0);
  model_.set_dynamics(std::nullopt);
  ActuatorModel probe(model_);
  probe.reset(opt_.input_min);
  const double y_span =
      std::abs(probe.peek_static(opt_.input_max) - probe.peek_static(opt_.input_min));
  y_tol_ = opt_.tolerance * std::max(y_span, 1e-300);
  u_prev_ = model_.last_input();
  const double dt = rate_sample_period(model_);
  if (const std::optional<ThresholdsRateLaw> law = model_.hysteresis().thresholds_law()) {
    // Widening thresholds (the rate-dependent PI's law, the plane's): where the output still
    // grows with the drive at its own rate each tick inverts exactly; else the drive is solved
    // at the rate the rate-free inverse's drive predicts.
    rate_free_ = make_inverse(rate_free_model(model_, opt_.input_min, opt_.input_max, u_prev_));
    // A prediction, so smoothed at least over a few samples even for the per-sample rate law.
    rate_free_rate_.configure(std::max(law->rate_filter_s, kMinRatePredictionSamples * dt), dt,
                              RateLaw::kThresholds);
    rate_free_rate_.reset(u_prev_);
    u_free_prev_ = u_prev_;
    max_rate_ = law->max_rate;
    own_rate_ = thresholds_grow_at_own_rate(*law, dt);
  } else if (model_.hysteresis().kind() == ModelKind::kRateDependentPi) {
    const auto& rpi = static_cast<const RateDependentPiModel&>(model_.hysteresis());
    const RateDependentPiParameters& p = rpi.parameters();
    rate_free_ = make_inverse(rate_free_model(model_, opt_.input_min, opt_.input_max, u_prev_));
    // A prediction, so smoothed at least over a few samples even for the per-sample rate law.
    rate_free_rate_.configure(std::max(p.rate_filter_s, kMinRatePredictionSamples * dt), dt,
                              p.rate_law);
    rate_free_rate_.reset(u_prev_);
    u_free_prev_ = u_prev_;
    for (const double w : p.base.play.weights) total_ += w;
    total_slope_ = p.rate_coefficients.empty() ? 0.0 : p.rate_coefficients.back();
    max_rate_ = p.max_rate;
    signed_ = p.rate_law == RateLaw::kSigned;
    if (signed_) {
      // Weights that grow with the signed rate: the output grows with u and with its own rate
      // on both branches, so the own-rate solution is exact and stable forward in time.
      own_rate_ = p.max_rate > 0.0 && rpi.grows_with_signed_rate();
    } else if (p.rate_filter_s == 0.0 && p.max_rate > 0.0) {
      window_ = static_cast<std::size_t>(std::clamp(std::ceil(kPreviewS / dt), 4.0, 1024.0));
      blend_ = std::min(1.0, dt / kFallingBlendS);
    }
  }
}

NumericInverse::NumericInverse(const NumericInverse& other)
    : model_(other.model_),
      opt_(other.opt_),
      u_prev_(other.u_prev_),
      y_tol_(other.y_tol_),
      rate_free_(other.rate_free_ ? other.rate_free_->clone() : nullptr),
      rate_free_rate_(other.rate_free_rate_),
      total_(other.total_),
      total_slope_(other.total_slope_),
      max_rate_(other.max_rate_),
      signed_(other.signed_),
      u_free_prev_(other.u_free_prev_),
      own_rate_(other.own_rate_),
      window_(other.window_),
      blend_(other.blend_),
      w_prev_(other.w_prev_),
      falling_(other.falling_) {}

double NumericInverse::solve(const ActuatorModel& model, double y_ref, double u_start,
                             double rate) const noexcept {
  return solve_with(y_ref, u_start, [&](double u) { return model.peek_static_at_rate(u, rate); });
}

template <typename Output>
double NumericInverse::solve_with(double y_ref, double u_start, Output output) const noexcept {
  const double lo_bound = opt_.input_min;
  const double hi_bound = opt_.input_max;
  auto f = [&](double u) { return output(u) - y_ref; };
  // Bracket around the previous input, growing the step geometrically: first in the direction
  // an increasing map suggests, then the other way.
  const double start = std::clamp(u_start, lo_bound, hi_bound);
  const double f_start = f(start);
  if (std::abs(f_start) <= y_tol_) return start;
  double a = start, fa = f_start, b = start, fb = f_start;
  bool bracketed = false;
  const double preferred = f_start < 0.0 ? 1.0 : -1.0;
  for (const double dir : {preferred, -preferred}) {
    a = start;
    fa = f_start;
    double stepsize = (hi_bound - lo_bound) * 1e-4;
    for (int it = 0; it < 64; ++it) {
      b = std::clamp(a + dir * stepsize, lo_bound, hi_bound);
      fb = f(b);
      if ((fb > 0.0) != (fa > 0.0) || std::abs(fb) <= y_tol_) {
        bracketed = true;
        break;
      }
      if (b == lo_bound || b == hi_bound) break;
      a = b;
      fa = fb;
      stepsize *= 2.0;
    }
    if (bracketed) break;
  }
  // Unreachable: saturate at the bound in the direction an increasing map suggests.
  if (!bracketed) return preferred > 0.0 ? hi_bound : lo_bound;
  // Regula falsi (Illinois) with bisection safeguard.
  int side = 0;
  for (int it = 0; it < opt_.max_iterations && std::abs(fb) > y_tol_; ++it) {
    double c = (fa * b - fb * a) / (fa - fb);
    if (!(c > std::min(a, b) && c < std::max(a, b))) c = 0.5 * (a + b);
    const double fc = f(c);
    if ((fc > 0.0) == (fb > 0.0)) {
      b = c;
      fb = fc;
      if (side == -1) fa *= 0.5;
      side = -1;
    } else {
      a = b;
      fa = fb;
      b = c;
      fb = fc;
      side = +1;
    }
    if (std::abs(b - a) <= 1e-15 * (std::abs(a) + std::abs(b) + 1e-300)) break;
  }
  return b;
}

double NumericInverse::step(double y_ref) noexcept {
  if (own_rate_) {
    // Signed rate law growing with the rate: the drive at its own (filtered) rate, exact.
    const double u = solve_with(y_ref, u_prev_, [&](double x) { return model_.peek_static(x); });
    model_.step(u);
    u_prev_ = u;
    return u;
  }
  double rate = 0.0;
  double step_bound = std::numeric_limits<double>::infinity();
  if (rate_free_) {
    // r W_n(r) = r_0 W_n(0): the rate-dependent map is steeper, so its drive moves slower.
    const double u_free = rate_free_->step(y_ref);
    double r0 = rate_free_rate_.step(u_free);
    if (signed_) {
      // A signed law whose weights fall with the rate: the drive's own rate raises the output
      // as it falls (a lag), so where the predicted rate turns at once (a triangle's corner) the
      // solved drive would jump and its own rate undo the solution. Its per-tick change stays
      // within twice the rate-free drive's (and a slow floor, so it can settle on a hold).
      step_bound = std::max(kSignedStepFactor * std::abs(u_free - u_free_prev_),
                            kSignedSettleRateFraction * max_rate_ * model_.sample_period());
      u_free_prev_ = u_free;
    }
    if (max_rate_ > 0.0) r0 = std::clamp(r0, signed_ ? -max_rate_ : 0.0, max_rate_);
    rate = r0;
    if (total_slope_ != 0.0 && total_ > 0.0) {
      // total_slope_ r^2 + total_ r - total_ r0 = 0, the positive root.
      const double disc = total_ * total_ + 4.0 * total_slope_ * total_ * r0;
      if (disc >= 0.0) rate = (2.0 * total_ * r0) / (total_ + std::sqrt(disc));
    }
  }
  const double u =
      std::clamp(solve(model_, y_ref, u_prev_, rate), u_prev_ - step_bound, u_prev_ + step_bound);
  model_.step(u);
  u_prev_ = u;
  return u;
}

double NumericInverse::falling_drive(std::span<const double> targets) const noexcept {
  const double dt = model_.sample_period();
  // The map's slope at rest just below the drive, for rates predicted from the targets.
  const double du = 1e-3 * (opt_.input_max - opt_.input_min);
  const double slope =
      (model_.peek_static_at_rate(u_prev_, 0.0) - model_.peek_static_at_rate(u_prev_ - du, 0.0)) /
      du;
  auto predicted_rate = [&](std::size_t j) {
    return slope > 0.0 ? (targets[j - 1] - targets[j]) / (dt * slope) : max_rate_;
  };
  // Falling faster than the rate cap, the map is static: solve this tick at the cap.
  if (predicted_rate(1) >= max_rate_) return solve(model_, targets[0], u_prev_, max_rate_);
  // The falling run ahead: targets[0 .. end] strictly decreasing.
  std::size_t end = 1;
  while (end + 1 < targets.size() && targets[end + 1] < targets[end]) ++end;
  // Its last sample: rate 0 where the run ends in the window (a reversal or a hold), else the
  // rate of the run's last step through the slope at rest (the error dies out backwards).
  const double rate = end + 1 == targets.size() ? std::min(predicted_rate(end), max_rate_) : 0.0;
  double u = solve(model_, targets[end], u_prev_, rate);
  for (std::size_t j = end; j > 0; --j) {
    // The previous sample of the drive is where this one's output needs it to come from.
    const double r = model_.rate_for_static_output(u, targets[j]);
    double u_before = u + (std::isfinite(r) ? std::min(r, max_rate_) : max_rate_) * dt;
    if (!(r < max_rate_)) {
      // Beyond the rate cap the map is static: the earlier sample is at least its static input.
      u_before = std::max(u_before, solve(model_, targets[j - 1], u, max_rate_));
    }
    u = std::min(u_before, opt_.input_max);
  }
  return u;
}

double NumericInverse::step_previewed(std::span<const double> targets) noexcept {
  if (window_ == 0 || targets.size() < 2) return step(targets.front());
  const double y_ref = targets.front();
  const double dt = model_.sample_period();
  double u = 0.0;
  if (targets[1] < y_ref) {
    const double w = falling_drive(targets);
    // Entering the run, the gap to the backward solution is the drive's distance from that
    // solution's previous sample; it closes over kFallingBlendS rather than in one tick.
    const double w_before =
        falling_
            ? w_prev_
            : w + std::min(std::max(model_.rate_for_static_output(w, y_ref), 0.0), max_rate_) * dt;
    u = std::clamp(w + (1.0 - blend_) * (u_prev_ - w_before), opt_.input_min, u_prev_);
    w_prev_ = w;
    falling_ = true;
  } else {
    // Rising or holding: the drive at its own per-sample rate (exact, stable forward), when
    // the target is above the output at rest; below it (the end of a fall, a step down) the
    // own rate would raise the output as the drive falls, so solve at rate 0 there.
    const double u0 = u_prev_;
    if (model_.peek_static_at_rate(u0, 0.0) < y_ref) {
      u = solve_with(y_ref, u0, [&](double x) {
        return model_.peek_static_at_rate(x, std::max(x - u0, 0.0) / dt);
      });
    } else {
      u = solve(model_, y_ref, u0, 0.0);
    }
    falling_ = false;
  }
  model_.step(u);
  u_prev_ = u;
  return u;
}

void NumericInverse::reset(double u0) noexcept {
  falling_ = false;
  model_.reset(u0);
  u_prev_ = u0;
  if (rate_free_) rate_free_->reset(u0);
  rate_free_rate_.reset(u0);
  u_free_prev_ = u0;
}

std::unique_ptr<InverseModel> NumericInverse::clone() const {
  return std::make_unique<NumericInverse>(*this);
}

// ---------------------------------------------------------------- InverseMultiplicative

InverseMultiplicativeCompensator::InverseMultiplicativeCompensator(const ActuatorModel& model,
                                                                   double gain)
    : model_(model), gain_(gain) {
  details::require(model_.valid(), "inverse multiplicative compensator needs a model");
  model_.set_delay(0.0);
  model_.set_dynamics(std::nullopt);
  if (!(gain_ > 0.0)) {
    details::require(model_.input_max > model_.input_min,
                     "inverse multiplicative compensator needs the model's input range or a gain");
    // Largest local slope along a major loop (min -> max -> min): with g at least every local
    // slope s, the per-sample correction factor 1 - s/g stays in [0, 1) and the structure is
    // stable everywhere; the mean slope can be less than half the steepest part and diverge.
    ActuatorModel probe(model_);
    probe.configure(model_.sample_period());
    probe.reset(model_.input_min);
    constexpr int kPoints = 2000;
    const double du = (model_.input_max - model_.input_min) / kPoints;
    double y_prev = probe.step(model_.input_min);
    gain_ = 0.0;
    for (int k = 1; k <= 2 * kPoints; ++k) {
      const double u =
          k <= kPoints ? model_.input_min + k * du : model_.input_max - (k - kPoints) * du;
      const double y = probe.step(u);
      gain_ = std::max(gain_, std::abs(y - y_prev) / du);
      y_prev = y;
    }
  }
  details::require(std::isfinite(gain_) && gain_ > 0.0,
                   "inverse multiplicative compensator needs a positive gain");
  // A weight rate law keeps one pass a tick (step()).
  const std::optional<ThresholdsRateLaw> law = model_.hysteresis().thresholds_law();
  iterate_ = law || model_.hysteresis().kind() != ModelKind::kRateDependentPi;
  tolerance_ = 1e-9 * std::max(std::abs(model_.input_max - model_.input_min), 1.0);
  u_prev_ = model_.last_input();
  y_prev_ = model_.peek_static(u_prev_);
  const double dt = rate_sample_period(model_);
  if (law && !thresholds_grow_at_own_rate(*law, dt)) {
    // The thresholds widen with |du/dt|: where the output still grows with the drive at its
    // own rate, the iteration contracts as for a static map; else each tick is solved at the
    // rate the rate-free structure's drive predicts.
    rate_free_ = std::make_unique<InverseMultiplicativeCompensator>(
        rate_free_model(model_, model_.input_min, model_.input_max, u_prev_));
    rate_.configure(std::max(law->rate_filter_s, kMinRatePredictionSamples * dt), dt,
                    RateLaw::kThresholds);
    rate_.reset(u_prev_);
  }
}

double InverseMultiplicativeCompensator::step(double y_ref) noexcept {
  double u = u_prev_ + (y_ref - y_prev_) / gain_;
  // The structure's equation u = u + (y_ref - H[u]) / g is implicit; one pass a tick, as the
  // delayed loop, leaves a lag of (g / s) ticks where the local slope s is low, which on a fast
  // reference costs more than the compensation gains. A rate-independent model is peeked without
  // advancing it, so the same equation is iterated to its fixed point within the tick (each pass
  // shrinks the error by 1 - s/g in [0, 1)); so is a thresholds law (see the constructor). A weight
  // rate law keeps one pass: its output moves with u's own rate, and an iteration through that
  // rate does not contract.
  if (iterate_) {
    const double rate = rate_free_ ? rate_.step(rate_free_->step(y_ref)) : 0.0;
    for (int i = 0; i < kMaxIterations; ++i) {
      const double y = rate_free_ ? model_.peek_static_at_rate(u, rate) : model_.peek_static(u);
      const double du = (y_ref - y) / gain_;
      u += du;
      if (std::abs(du) <= tolerance_) break;
    }
  }
  y_prev_ = model_.step(u);
  u_prev_ = u;
  return u;
}

InverseMultiplicativeCompensator::InverseMultiplicativeCompensator(
    const InverseMultiplicativeCompensator& other)
    : model_(other.model_),
      gain_(other.gain_),
      u_prev_(other.u_prev_),
      y_prev_(other.y_prev_),
      iterate_(other.iterate_),
      tolerance_(other.tolerance_),
      rate_free_(other.rate_free_
                     ? std::make_unique<InverseMultiplicativeCompensator>(*other.rate_free_)
                     : nullptr),
      rate_(other.rate_) {}

void InverseMultiplicativeCompensator::reset(double u0) noexcept {
  if (rate_free_) rate_free_->reset(u0);
  rate_.reset(u0);
  model_.reset(u0);
  u_prev_ = u0;
  y_prev_ = model_.peek_static(u0);
}

std::unique_ptr<InverseModel> InverseMultiplicativeCompensator::clone() const {
  return std::make_unique<InverseMultiplicativeCompensator>(*this);
}

std::vector<double> invert_sequence(InverseModel& inverse, std::span<const double> targets) {
  const std::size_t ahead = std::max<std::size_t>(inverse.preview_samples(), 1);
  std::vector<double> u(targets.size());
  for (std::size_t k = 0; k < targets.size(); ++k) {
    u[k] = inverse.step_previewed(targets.subspan(k, std::min(ahead, targets.size() - k)));
  }
  return u;
}

// ---------------------------------------------------------------- factory

std::unique_ptr<InverseModel> make_inverse(const ActuatorModel& model, InverseKind kind) {
  details::require(model.valid(), "cannot invert an empty model");
  const Invertibility inv = model.hysteresis().invertibility();
  if (!inv.invertible) throw NotInvertibleError(inv);
  const ModelKind mk = model.hysteresis().kind();
  const bool analytic_possible =
      !model.creep() && (mk == ModelKind::kPi || mk == ModelKind::kModifiedPi);
  if (kind == InverseKind::kAuto)
    kind = analytic_possible ? InverseKind::kAnalytic : InverseKind::kNumeric;
  switch (kind) {
    case InverseKind::kAnalytic:
      details::require(analytic_possible, "no analytic inverse for a " +
                                              std::string(to_string(mk)) +
                                              (model.creep() ? " model with creep" : " model") +
                                              "; use the numeric inverse");
      if (mk == ModelKind::kPi) {
        return std::make_unique<PiInverse>(static_cast<const PiModel&>(model.hysteresis()),
                                           InputRange{model.input_min, model.input_max});
      }
      return std::make_unique<ModifiedPiInverse>(
          static_cast<const ModifiedPiModel&>(model.hysteresis()),
          InputRange{model.input_min, model.input_max});
    case InverseKind::kNumeric:
      return std::make_unique<NumericInverse>(model);
    case InverseKind::kMultiplicative:
      return std::make_unique<InverseMultiplicativeCompensator>(model);
    case InverseKind::kAuto:
      break;
  }
  throw std::invalid_argument("unknown inverse kind");
}

}  // namespace hystbench::compensation
