#include "hystbench/compensation/drive_planner.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "details/validate.hpp"
#include "hystbench/compensation/creep_operator_bank.hpp"
#include "hystbench/compensation/dead_zone.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/compensation/rate_estimator.hpp"

namespace hystbench::compensation {

namespace {

// The model's static path (rate-dependent PI hysteresis plus creep) in the form the planner
// differentiates: y = center + S[offset + sum_i (w_i + dw_i rho) p_i - center] + sum_j g_j x_j,
// rho = min(|v|, max_rate) (signed law: v clamped to +-max_rate), v the rate's low-pass, x_j the
// creep lags.
struct StaticPath {
  std::vector<double> r, w, dw;
  double offset = 0.0, center = 0.0;
  DeadZoneSuperposition dz;
  double max_rate = 0.0;
  double a = 1.0;  // the rate filter's coefficient (1: the per-sample difference)
  bool signed_law = false;
  double dt = 1e-3;
  std::vector<double> creep_a, creep_g;

  std::size_t plays() const noexcept { return r.size(); }
};

struct PathState {
  std::vector<double> play;
  double u_prev = 0.0;
  double v = 0.0;
  std::vector<double> creep;
};

StaticPath static_path(const ActuatorModel& model) {
  const auto& h = dynamic_cast<const RateDependentPiModel&>(model.hysteresis());
  const RateDependentPiParameters& p = h.parameters();
  StaticPath s;
  s.r = p.base.play.thresholds;
  s.w = p.base.play.weights;
  s.dw.assign(h.rate_slopes().begin(), h.rate_slopes().end());
  s.offset = p.base.play.offset;
  s.center = p.base.center;
  s.dz = DeadZoneSuperposition(p.base.dead_zone);
  s.max_rate = p.max_rate;
  s.signed_law = p.rate_law == RateLaw::kSigned;
  s.dt = h.sample_period();
  s.a = RateEstimator(p.rate_filter_s, s.dt).coefficient();
  if (const auto& c = model.creep()) {
    const CreepOperatorBank bank(*c, s.dt);
    s.creep_a.assign(bank.coefficients().begin(), bank.coefficients().end());
    s.creep_g = c->gains;
  }
  return s;
}

PathState relaxed(const StaticPath& s, double u0) {
  return {std::vector<double>(s.plays(), u0), u0, 0.0, std::vector<double>(s.creep_a.size(), u0)};
}

// One chunk of the plan: the forward pass with what the Jacobian needs, and the Jacobian's
// products with a vector and with its transpose.
class Chunk {
 public:
  static constexpr double kStepWeight = 10.0;  // [output unit per input unit beyond the bound]

  // `step_bound` > 0: per-tick drive changes beyond it are penalised (kStepWeight per V), from
  // sample `bound_from` on (the plan's first sample may jump from where the prefix left it).
  Chunk(const StaticPath& s, std::span<const double> targets, double step_bound = 0.0,
        std::size_t bound_from = 0)
      : s_(s),
        targets_(targets),
        n_(targets.size()),
        np_(s.plays()),
        step_bound_(step_bound),
        bound_from_(bound_from) {}

  // Simulates u from `start`; returns the sum of squared errors. With `record` keeps the
  // Jacobian's entries (allocated then: a chunk that only simulates holds none). `end` (when not
  // null) receives the state after `count` samples.
  double forward(std::span<const double> u, const PathState& start, bool record,
                 std::vector<double>* gain = nullptr, PathState* end = nullptr,
                 std::size_t count = 0) {
    if (record && residual_.empty()) {
      last_.resize(n_ * np_);
      coef_.resize(n_ * np_);
      rate_gain_.resize(n_);
      step_sign_.resize(n_);
      residual_.resize(2 * n_);
    }
    PathState st = start;
    std::vector<std::int32_t> last(np_, -1);
    double cost = 0.0;
    for (std::size_t k = 0; k < n_; ++k) {
      if (end != nullptr && k == count) *end = st;
      const double uk = u[k];
      const double du = uk - st.u_prev;
      const double excess =
          step_bound_ > 0.0 && k >= bound_from_ ? std::abs(du) - step_bound_ : 0.0;
      if (excess > 0.0) cost += kStepWeight * kStepWeight * excess * excess;
      if (record) {
        step_sign_[k] = excess > 0.0 ? (du > 0.0 ? 1.0 : -1.0) : 0.0;
        residual_[n_ + k] = excess > 0.0 ? kStepWeight * excess : 0.0;
      }
      st.v += s_.a * ((uk - st.u_prev) / s_.dt - st.v);
      st.u_prev = uk;
      double rho = s_.signed_law ? st.v : std::abs(st.v);
      const bool capped = s_.max_rate > 0.0 && std::abs(rho) > s_.max_rate;
      if (capped) rho = std::copysign(s_.max_rate, rho);
      double h = s_.offset, per_rate = 0.0, total_w = 0.0;
      for (std::size_t i = 0; i < np_; ++i) {
        double& pl = st.play[i];
        if (uk - s_.r[i] > pl) {
          pl = uk - s_.r[i];
          last[i] = static_cast<std::int32_t>(k);
        } else if (uk + s_.r[i] < pl) {
          pl = uk + s_.r[i];
          last[i] = static_cast<std::int32_t>(k);
        }
        const double wi = s_.w[i] + s_.dw[i] * rho;
        h += wi * pl;
        per_rate += s_.dw[i] * pl;
        total_w += wi;
      }
      const double dz = s_.dz.slope(h - s_.center);
      double y = s_.center + s_.dz.apply(h - s_.center), creep_slope = 0.0;
      for (std::size_t j = 0; j < st.creep.size(); ++j) {
        st.creep[j] = s_.creep_a[j] * st.creep[j] + (1.0 - s_.creep_a[j]) * uk;
        y += s_.creep_g[j] * st.creep[j];
        creep_slope += s_.creep_g[j];
      }
      const double e = y - targets_[k];
      cost += e * e;
      if (record) {
        residual_[k] = e;
        for (std::size_t i = 0; i < np_; ++i) {
          last_[k * np_ + i] = last[i];
          coef_[k * np_ + i] = dz * (s_.w[i] + s_.dw[i] * rho);
        }
        const double sign = s_.signed_law ? 1.0 : (st.v > 0.0 ? 1.0 : (st.v < 0.0 ? -1.0 : 0.0));
        rate_gain_[k] = capped ? 0.0 : dz * per_rate * sign;
      }
      if (gain != nullptr) (*gain)[k] = std::max(dz * total_w + creep_slope, 1e-12);
    }
    if (end != nullptr && count >= n_) *end = st;
    return cost;
  }

  // out = J x (out: the n outputs' rows, then the n step penalties')
  void jacobian_times(std::span<const double> x, std::span<double> out) const {
    const double b = s_.a / s_.dt;
    double dv = 0.0, x_prev = 0.0;
    std::vector<double> dc(s_.creep_a.size(), 0.0);
    for (std::size_t k = 0; k < n_; ++k) {
      double d = 0.0;
      for (std::size_t i = 0; i < np_; ++i) {
        const std::int32_t m = last_[k * np_ + i];
        if (m >= 0) d += coef_[k * np_ + i] * x[static_cast<std::size_t>(m)];
      }
      dv = (1.0 - s_.a) * dv + b * (x[k] - x_prev);
      x_prev = x[k];
      d += rate_gain_[k] * dv;
      for (std::size_t j = 0; j < dc.size(); ++j) {
        dc[j] = s_.creep_a[j] * dc[j] + (1.0 - s_.creep_a[j]) * x[k];
        d += s_.creep_g[j] * dc[j];
      }
      out[k] = d;
      out[n_ + k] = kStepWeight * step_sign_[k] * (x[k] - (k > 0 ? x[k - 1] : 0.0));
    }
  }

  // out = J^T e
  void transpose_times(std::span<const double> e, std::span<double> out) const {
    std::fill(out.begin(), out.end(), 0.0);
    const double b = s_.a / s_.dt;
    double lambda = 0.0;
    std::vector<double> mu(s_.creep_a.size(), 0.0);
    for (std::size_t k = n_; k-- > 0;) {
      for (std::size_t i = 0; i < np_; ++i) {
        const std::int32_t m = last_[k * np_ + i];
        if (m >= 0) out[static_cast<std::size_t>(m)] += coef_[k * np_ + i] * e[k];
      }
      const double penalty = kStepWeight * step_sign_[k] * e[n_ + k];
      out[k] += penalty;
      if (k > 0) out[k - 1] -= penalty;
      lambda = rate_gain_[k] * e[k] + (1.0 - s_.a) * lambda;
      out[k] += b * lambda;
      if (k > 0) out[k - 1] -= b * lambda;
      for (std::size_t j = 0; j < mu.size(); ++j) {
        mu[j] = s_.creep_g[j] * e[k] + s_.creep_a[j] * mu[j];
        out[k] += (1.0 - s_.creep_a[j]) * mu[j];
      }
    }
  }

  // The diagonal of J^T J from each row's direct entries (the rate filter's and the creep lags'
  // tails left out): the conjugate gradients' preconditioner.
  void normal_diagonal(std::span<double> out) const {
    std::fill(out.begin(), out.end(), 0.0);
    const double b = s_.a / s_.dt;
    double creep_direct = 0.0;
    for (std::size_t j = 0; j < s_.creep_a.size(); ++j)
      creep_direct += s_.creep_g[j] * (1.0 - s_.creep_a[j]);
    for (std::size_t k = 0; k < n_; ++k) {
      double own = rate_gain_[k] * b + creep_direct;
      for (std::size_t i = 0; i < np_; ++i) {
        const std::int32_t m = last_[k * np_ + i];
        if (m < 0) continue;
        const double c = coef_[k * np_ + i];
        if (static_cast<std::size_t>(m) == k) {
          own += c;
        } else {
          out[static_cast<std::size_t>(m)] += c * c;
        }
      }
      out[k] += own * own;
      if (k > 0) out[k - 1] += rate_gain_[k] * b * rate_gain_[k] * b;
      if (step_sign_[k] != 0.0) {
        out[k] += kStepWeight * kStepWeight;
        if (k > 0) out[k - 1] += kStepWeight * kStepWeight;
      }
    }
  }

  std::span<const double> residual() const noexcept { return residual_; }
  std::size_t size() const noexcept { return n_; }

 private:
  const StaticPath& s_;
  std::span<const double> targets_;
  std::size_t n_, np_;
  double step_bound_;
  std::size_t bound_from_;
  std::vector<double> step_sign_;   // per sample: sign of a drive change beyond the bound, or 0
  std::vector<std::int32_t> last_;  // per sample and play: the tick the play last moved, or -1
  std::vector<double> coef_;        // per sample and play: d y / d play output
  std::vector<double> rate_gain_;   // per sample: d y / d v (0 where the rate is capped)
  std::vector<double> residual_;
};

double dot(std::span<const double> a, std::span<const double> b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
  return s;
}

// Solves (J^T J + mu I) step = -J^T e approximately by preconditioned conjugate gradients.
std::vector<double> lm_step(const Chunk& c, std::span<const double> diag, double mu,
                            int iterations) {
  const std::size_t n = c.size();
  std::vector<double> rhs(n), x(n, 0.0), p(n), q(n), jp(2 * n), z(n);
  c.transpose_times(c.residual(), rhs);
  for (double& v : rhs) v = -v;
  std::vector<double> res = rhs;
  for (std::size_t i = 0; i < n; ++i) z[i] = res[i] / (diag[i] + mu);
  p = z;
  double rz = dot(res, z);
  const double stop = 1e-10 * dot(rhs, rhs);
  for (int it = 0; it < iterations && dot(res, res) > stop; ++it) {
    c.jacobian_times(p, jp);
    c.transpose_times(jp, q);
    for (std::size_t i = 0; i < n; ++i) q[i] += mu * p[i];
    const double pq = dot(p, q);
    if (!(pq > 0.0)) break;
    const double alpha = rz / pq;
    for (std::size_t i = 0; i < n; ++i) {
      x[i] += alpha * p[i];
      res[i] -= alpha * q[i];
    }
    for (std::size_t i = 0; i < n; ++i) z[i] = res[i] / (diag[i] + mu);
    const double rz_new = dot(res, z);
    const double beta = rz_new / rz;
    rz = rz_new;
    for (std::size_t i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
  }
  return x;
}

// Levenberg-Marquardt over the drive u of one chunk (in place); `done_before` and `share` place
// its progress in the whole plan.
void plan_chunk(const StaticPath& s, const PathState& start, std::span<const double> targets,
                std::span<double> u, double lo, double hi, double step_bound,
                std::size_t bound_from, const DrivePlanOptions& o, double done_before,
                double share) {
  Chunk c(s, targets, step_bound, bound_from);
  double cost = c.forward(u, start, true);
  std::vector<double> diag(u.size()), trial(u.size());
  c.normal_diagonal(diag);
  double mean_diag = 0.0;
  for (const double d : diag) mean_diag += d;
  mean_diag /= static_cast<double>(diag.size());
  double mu = 1e-3 * mean_diag;
  Chunk t(s, targets, step_bound, bound_from);
  for (int it = 0; it < o.iterations && cost > 0.0; ++it) {
    bool accepted = false;
    while (!accepted && mu < 1e12 * mean_diag) {
      const std::vector<double> step = lm_step(c, diag, mu, o.cg_iterations);
      for (std::size_t k = 0; k < u.size(); ++k) trial[k] = std::clamp(u[k] + step[k], lo, hi);
      const double trial_cost = t.forward(trial, start, false);
      if (trial_cost < cost) {
        accepted = true;
        const bool small = cost - trial_cost < 1e-6 * cost;
        std::copy(trial.begin(), trial.end(), u.begin());
        cost = c.forward(u, start, true);
        c.normal_diagonal(diag);
        mu = std::max(mu / 3.0, 1e-9 * mean_diag);
        if (small) it = o.iterations;
      } else {
        mu *= 4.0;
      }
    }
    if (o.progress) {
      o.progress(done_before + share * std::min(1.0, static_cast<double>(it + 1) / o.iterations));
    }
    if (!accepted) break;
  }
}

// The largest per-tick change of the rate-free (modified PI) inverse's drive over the targets.
double rate_free_max_step(const ActuatorModel& model, double u_start,
                          std::span<const double> prefix, std::span<const double> targets) {
  const auto& h = dynamic_cast<const RateDependentPiModel&>(model.hysteresis());
  ActuatorModel m(std::make_unique<ModifiedPiModel>(h.parameters().base));
  m.set_creep(model.creep());
  m.input_min = model.input_min;
  m.input_max = model.input_max;
  m.configure(model.sample_period());
  m.reset(u_start);
  for (const double u : prefix) m.step(u);
  const std::unique_ptr<InverseModel> inverse = make_inverse(m);
  double largest = 0.0, previous = inverse->step(targets.front());
  for (std::size_t k = 1; k < targets.size(); ++k) {
    const double u = inverse->step(targets[k]);
    largest = std::max(largest, std::abs(u - previous));
    previous = u;
  }
  return largest;
}

// The gain's steps where the output crosses a dead zone's threshold would put steps into a
// correction through it: averaged over this window [s].
constexpr double kGainSmoothingS = 0.005;

// Centred moving average over `window` samples (shorter at the ends).
std::vector<double> smoothed(const std::vector<double>& x, std::size_t window) {
  const std::size_t half = window / 2, n = x.size();
  if (half == 0) return x;
  std::vector<double> prefix(n + 1, 0.0), out(n);
  for (std::size_t k = 0; k < n; ++k) prefix[k + 1] = prefix[k] + x[k];
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t lo = k > half ? k - half : 0, hi = std::min(n, k + half + 1);
    out[k] = (prefix[hi] - prefix[lo]) / static_cast<double>(hi - lo);
  }
  return out;
}

// The least gain a correction divides by, as a fraction of the plan's mean slope (the
// targets' span over the drive's): where the model's local slope is near zero (a dead zone's
// flat side, weights that fall with the rate) a small target offset, such as the tare's, would
// otherwise move the drive to its limit.
constexpr double kGainFloorFraction = 0.1;

void floor_gain(std::vector<double>& gain, std::span<const double> targets,
                std::span<const double> u) {
  const auto [t_lo, t_hi] = std::minmax_element(targets.begin(), targets.end());
  const auto [u_lo, u_hi] = std::minmax_element(u.begin(), u.end());
  const double mean_slope = (*t_hi - *t_lo) / (*u_hi - *u_lo);
  if (!(std::isfinite(mean_slope) && mean_slope > 0.0)) return;
  for (double& g : gain) g = std::max(g, kGainFloorFraction * mean_slope);
}

}  // namespace

bool can_plan_drive(const ActuatorModel& model) noexcept {
  if (!model.valid() || model.hysteresis().kind() != ModelKind::kRateDependentPi) return false;
  const auto* h = dynamic_cast<const RateDependentPiModel*>(&model.hysteresis());
  if (h == nullptr) return false;
  // A signed rate law whose weights grow with the rate is inverted exactly, forward in time, by
  // the previewed inverse (its drive at its own rate): nothing is left to plan. The plan's
  // Jacobian is that of the weight laws; the thresholds law is inverted tick by tick.
  // A law that changes nothing with the rate (the modified PI nested in the family) leaves the
  // previewed inverse exact too.
  return !h->rate_free() && !h->grows_with_signed_rate() &&
         h->parameters().rate_law != RateLaw::kThresholds;
}

double plan_drive_work(const ActuatorModel& model, std::size_t samples) noexcept {
  if (!can_plan_drive(model)) return 0.0;
  const auto& p = static_cast<const RateDependentPiModel&>(model.hysteresis()).parameters();
  return static_cast<double>(samples) * static_cast<double>(p.base.play.thresholds.size() + 2);
}

DrivePlan plan_drive(const ActuatorModel& model, double u_start, std::span<const double> prefix,
                     std::span<const double> targets, const DrivePlanOptions& options) {
  details::require(can_plan_drive(model),
                   "plan_drive: the model is not a rate-dependent PI (nothing to plan)");
  details::require(!targets.empty(), "plan_drive: no targets");
  details::require(std::isfinite(u_start), "plan_drive: u_start must be finite");
  details::require_finite(prefix, "plan_drive: prefix");
  details::require_finite(targets, "plan_drive: targets");
  details::require(options.iterations >= 1 && options.cg_iterations >= 1,
                   "plan_drive: iterations and cg_iterations must be >= 1");
  details::require(options.chunk_samples >= 1, "plan_drive: chunk_samples must be >= 1");
  double lo = options.input_min, hi = options.input_max;
  if (!(lo < hi)) {
    lo = model.input_min;
    hi = model.input_max;
  }
  details::require(lo < hi, "plan_drive: the drive range is empty (set input_min < input_max)");

  // The start: the previewed inverse's drive, from the state the prefix leaves.
  const std::size_t n = targets.size();
  DrivePlan plan;
  {
    ActuatorModel m = model;
    m.reset(u_start);
    for (const double u : prefix) m.step(u);
    plan.u = invert_sequence(*make_inverse(m), targets);
    for (double& u : plan.u) u = std::clamp(u, lo, hi);
  }

  const double step_bound =
      options.max_step_factor > 0.0
          ? options.max_step_factor * rate_free_max_step(model, u_start, prefix, targets)
          : 0.0;
  const StaticPath model_path = static_path(model);
  StaticPath s = model_path;  // the law the plan is optimised on
  const auto& rpi = dynamic_cast<const RateDependentPiModel&>(model.hysteresis()).parameters();
  if (!options.hold_rate_beyond_max.value_or(rpi.record_max_rate > rpi.max_rate)) {
    s.max_rate = 0.0;
  }
  PathState state = relaxed(s, u_start);  // the state does not depend on the held rate
  if (!prefix.empty()) {
    Chunk c(s, prefix);  // the prefix's own values as targets: only the state is wanted
    c.forward(prefix, state, false, nullptr, &state, prefix.size());
  }
  const PathState after_prefix = state;
  {
    Chunk whole(model_path, targets);
    plan.start_rms = std::sqrt(whole.forward(plan.u, after_prefix, false) / static_cast<double>(n));
  }
  const std::size_t chunk = options.chunk_samples;
  const bool start_is_good_enough = plan.start_rms <= options.accept_start_rms;
  for (std::size_t begin = 0; begin < n && !start_is_good_enough; begin += chunk) {
    const std::size_t end = std::min(n, begin + chunk + options.overlap_samples);
    const std::size_t keep = std::min(chunk, n - begin);
    const std::span<double> u(plan.u.data() + begin, end - begin);
    const std::span<const double> t = targets.subspan(begin, end - begin);
    plan_chunk(s, state, t, u, lo, hi, step_bound, begin == 0 ? 1 : 0, options,
               static_cast<double>(begin) / n, static_cast<double>(keep) / n);
    Chunk c(s, t);
    c.forward(u, state, false, nullptr, &state, keep);
  }
  // The plan's figures are the model's own (its rate law held beyond max_rate).
  std::vector<double> gain(n);
  Chunk whole(model_path, targets);
  plan.rms = std::sqrt(whole.forward(plan.u, after_prefix, false, &gain) / static_cast<double>(n));
  plan.gain = smoothed(gain, static_cast<std::size_t>(std::lround(kGainSmoothingS / s.dt)));
  floor_gain(plan.gain, targets, plan.u);
  if (options.progress) options.progress(1.0);
  return plan;
}

DrivePlan continue_periodic_plan(DrivePlan plan, double period_samples, std::size_t samples) {
  const std::size_t n = plan.u.size();
  details::require(std::isfinite(period_samples) && period_samples > 1.0 && n >= 2 &&
                       2.0 * period_samples <= static_cast<double>(n - 1),
                   "continue_periodic_plan: the period must be longer than a sample and the "
                   "plan at least two periods long");
  details::require(plan.gain.size() == n, "continue_periodic_plan: drive and gain differ");
  details::require(samples >= n, "continue_periodic_plan: fewer samples than the plan holds");
  // The plan's last period had no future to balance against: the one before it repeats.
  const double end = static_cast<double>(n - 1) - period_samples;
  const auto first = static_cast<std::size_t>(std::floor(end)) + 1;
  plan.u.resize(samples);
  plan.gain.resize(samples);
  for (std::size_t k = first; k < samples; ++k) {
    // The same phase in the repeated period, [end - P, end].
    const double back = std::ceil((static_cast<double>(k) - end) / period_samples);
    const double t = std::max(static_cast<double>(k) - back * period_samples, 0.0);
    const auto i = std::min(static_cast<std::size_t>(t), first - 2);
    const double a = t - static_cast<double>(i);
    plan.u[k] = (1.0 - a) * plan.u[i] + a * plan.u[i + 1];
    plan.gain[k] = (1.0 - a) * plan.gain[i] + a * plan.gain[i + 1];
  }
  return plan;
}

}  // namespace hystbench::compensation
