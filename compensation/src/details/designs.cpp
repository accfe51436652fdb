#include "details/designs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "details/preisach_smoothness.hpp"
#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/compensation/rate_estimator.hpp"

namespace hystbench::compensation::details {

namespace {
constexpr double kUnbounded = std::numeric_limits<double>::infinity();
}  // namespace

std::size_t ModelStructure::zero_index() const {
  const auto it = std::find(dead_zone_thresholds.begin(), dead_zone_thresholds.end(), 0.0);
  if (it == dead_zone_thresholds.end()) {
    throw std::invalid_argument("dead-zone thresholds must contain 0");
  }
  return static_cast<std::size_t>(it - dead_zone_thresholds.begin());
}

void add_drift(const ModelStructure& s, double per_s, std::span<double> y) noexcept {
  if (per_s == 0.0) return;
  for (std::size_t k = 0; k < y.size(); ++k) y[k] += per_s * s.drift_time_s(k);
}

CoupledThresholds coupled_thresholds(const ModelStructure& s) {
  CoupledThresholds t;
  t.r = s.play_thresholds;
  for (const double r : t.r) {
    t.ra.push_back(s.cp_scale[0] * r);
    t.rb.push_back(s.cp_scale[1] * r);
    t.rc.push_back(s.cp_scale[2] * r);
  }
  return t;
}

std::vector<double> sample_rates(std::span<const double> u, double dt, double rate_filter_s) {
  return estimate_rates(u, dt, rate_filter_s);
}

Design::Design(ModelStructure s) : s_(std::move(s)) {
  if (s_.kind == ModelKind::kPreisach) {
    const std::size_t n = s_.preisach_cells;
    const bool shaped = !s_.preisach_shape.empty();
    PreisachParameters plane{
        s_.plane_min, s_.plane_max, n,
        shaped ? s_.preisach_shape : std::vector<double>(PreisachModel::cell_count(n), 0.0)};
    if (s_.rate_law == RateLaw::kThresholds) plane.rate_law = s_.thresholds_law();
    plane_ = std::make_unique<PreisachModel>(std::move(plane));
    plane_->set_sample_period(s_.dt);
    s_.play_thresholds.clear();
    n_ = shaped ? 1 : static_cast<Eigen::Index>(PreisachModel::cell_count(n));
  } else if (s_.play_thresholds.empty()) {
    throw std::invalid_argument("a design needs at least one play");
  } else {
    n_ = static_cast<Eigen::Index>(s_.plays());
  }
  if (s_.kind == ModelKind::kRateDependentPi) s_.input_reference = 0.0;  // see header
  if (s_.kind == ModelKind::kCoupledPlayPi) {
    cp_ = coupled_thresholds(s_);
    increments_ = s_.cp_scale[2] > 1.0 || s_.cp_scale[0] < s_.cp_scale[1];
  }
  if (s_.has_dead_zones()) {
    const std::size_t zero = s_.zero_index();
    for (std::size_t j = zero + 1; j < s_.dead_zone_thresholds.size(); ++j) {
      dz_pos_.push_back(s_.dead_zone_thresholds[j]);
    }
    for (std::size_t j = zero; j-- > 0;) dz_neg_.push_back(s_.dead_zone_thresholds[j]);
  }
  m_pos_ = static_cast<Eigen::Index>(dz_pos_.size());
  m_neg_ = static_cast<Eigen::Index>(dz_neg_.size());
  if (s_.kind == ModelKind::kRateDependentPi) {
    if (!(s_.max_rate > 0.0))
      throw std::invalid_argument("rate-dependent design needs max_rate > 0");
    inv_max_rate_ = 1.0 / s_.max_rate;
    rate_.configure(s_.rate_filter_s, s_.dt, s_.rate_law);
  }
  play_cols_ = s_.kind == ModelKind::kRateDependentPi && !thresholds_law() ? 2 * n_ : n_;
  if (plane_) play_cols_ = n_ + 1;  // the cells, then the reversible slope
  offset_col_ = play_cols_;
  dz_col_ = offset_col_ + 1;
  creep_col_ = dz_col_ + m_pos_ + m_neg_;
  drift_col_ = creep_col_ + static_cast<Eigen::Index>(s_.creep_time_constants.size());
  unknowns_ = drift_col_ + (s_.drift ? 1 : 0);
  z_.assign(s_.plays(), 0.0);
  for (const double tau : s_.creep_time_constants) creep_a_.push_back(std::exp(-s_.dt / tau));
  creep_x_.assign(creep_a_.size(), 0.0);
}

void Design::reset(double u0) noexcept {
  if (plane_) plane_->reset(u0);
  std::fill(z_.begin(), z_.end(), u0);
  std::fill(creep_x_.begin(), creep_x_.end(), u0);
  u_prev_ = u0;
  sample_ = 0;
  rate_.reset(u0);
}

void Design::step_operators(double u, double widen) noexcept {
  const double* r = s_.play_thresholds.data();
  double* z = z_.data();
  if (s_.kind == ModelKind::kCoupledPlayPi) {
    for (Eigen::Index i = 0; i < n_; ++i) {
      z[i] = CoupledPlayPiModel::operator_output(u, u_prev_, z[i], r[i], cp_.ra[i], cp_.rb[i],
                                                 cp_.rc[i]);
    }
  } else {
    for (Eigen::Index i = 0; i < n_; ++i) {
      const double ri = r[i] > 0.0 ? r[i] + widen : 0.0;  // the linear term does not lag
      z[i] = std::max(u - ri, std::min(u + ri, z[i]));
    }
  }
}

void Design::step_relays_and_lags(double u) noexcept {
  if (plane_) {
    if (s_.preisach_shape.empty()) {
      plane_->step_relays(u);
    } else {
      (void)plane_->step(u);
    }
  }
  for (std::size_t k = 0; k < creep_x_.size(); ++k) {
    creep_x_[k] = creep_a_[k] * creep_x_[k] + (1.0 - creep_a_[k]) * u;
  }
  ++sample_;
  u_prev_ = u;
}

double Design::step(double u, double y, double* a) noexcept {
  // The model's rate: filtered, capped at max_rate (rho in [0, 1], signed: [-1, 1]).
  const double rho = s_.kind == ModelKind::kRateDependentPi
                         ? std::clamp(rate_.step(u) * inv_max_rate_, -1.0, 1.0)
                         : 0.0;
  if (!plane_) {
    step_operators(u, thresholds_law()
                          ? threshold_widening(s_.threshold_rate_s, s_.threshold_rate_exponent,
                                               s_.max_rate, std::abs(rho) * s_.max_rate)
                          : 0.0);
  }
  if (a == nullptr) {  // skip()
    step_relays_and_lags(u);
    return 0.0;
  }
  // Cumulative-weight regressors: sum_i w_i (p_i - u_ref) = sum_i W_i (p_i - p_{i+1}).
  const double* z = z_.data();
  if (plane_) {
    if (s_.preisach_shape.empty()) {
      plane_->step_cell_areas(u, std::span<double>(a, static_cast<std::size_t>(n_)));
    } else {
      a[0] = plane_->step(u);  // no slope, offset or map: the shape's relays alone
    }
    a[n_] = u - s_.input_reference;
  } else if (thresholds_law()) {
    for (Eigen::Index i = 0; i < n_; ++i) a[i] = z[i] - (i + 1 < n_ ? z[i + 1] : 0.0);
  } else if (s_.kind == ModelKind::kRateDependentPi) {
    const bool signed_law = s_.rate_law == RateLaw::kSigned;
    for (Eigen::Index i = 0; i < n_; ++i) {
      const double q = z[i] - (i + 1 < n_ ? z[i + 1] : 0.0);
      a[i] = q;
      // Signed: sum_i (1 - rho) C_i q_i = (1 - rho) sum_j e_j p_j (C_i = sum_{j<=i} e_j).
      a[n_ + i] = signed_law ? (1.0 - rho) * z[i] : q * rho;
    }
  } else if (increments_) {
    for (Eigen::Index i = 0; i < n_; ++i) a[i] = z[i] - s_.input_reference;
  } else {
    for (Eigen::Index i = 0; i + 1 < n_; ++i) a[i] = z[i] - z[i + 1];
    a[n_ - 1] = z[n_ - 1] - s_.input_reference;
  }
  a[offset_col_] = 1.0;
  double target = plane_ && !s_.has_dead_zones() ? y - s_.center : y;
  if (s_.has_dead_zones()) {
    // S'[v] = clamp(v, d'_-1, d'_1) + sum_j V_j t_j per side, t_j = s_j - s_{j+1}.
    const double v = y - s_.center;
    double* t = a + dz_col_;
    double next = 0.0;
    for (Eigen::Index j = m_pos_; j-- > 0;) {
      const double sj = std::max(v - dz_pos_[j], 0.0);
      t[j] = -(sj - next);
      next = sj;
    }
    t += m_pos_;
    next = 0.0;
    for (Eigen::Index j = m_neg_; j-- > 0;) {
      const double sj = std::min(v - dz_neg_[j], 0.0);
      t[j] = -(sj - next);
      next = sj;
    }
    target =
        std::clamp(v, m_neg_ > 0 ? dz_neg_[0] : -kUnbounded, m_pos_ > 0 ? dz_pos_[0] : kUnbounded);
  }
  double* c = a + creep_col_;
  for (std::size_t k = 0; k < creep_x_.size(); ++k) {
    creep_x_[k] = creep_a_[k] * creep_x_[k] + (1.0 - creep_a_[k]) * u;
    c[k] = creep_x_[k];
  }
  if (s_.drift) a[drift_col_] = s_.drift_time_s(sample_);
  ++sample_;
  u_prev_ = u;
  return target;
}

Eigen::VectorXd Design::lower_bounds() const {
  Eigen::VectorXd lo = Eigen::VectorXd::Constant(unknowns_, -kUnbounded);
  lo.head(n_).setConstant(s_.min_play_slope);
  // Jumping coupled plays: w_0 >= eps and w_i >= 0, so every cumulative weight is >= eps too.
  if (increments_) lo.segment(1, n_ - 1).setConstant(0.0);
  // RPI: the rate parts D_i = W_i(max_rate) - W_i(0) >= 0: the loop widens with rate (the
  // rate-dependent paper's Fig. 8), and W_i >= eps holds on all of [0, max_rate]. Signed law:
  // the head is W_i(+max_rate) >= eps and every play's rate slope -e_j <= 0: the loading slope
  // falls with the rate and the unloading one rises, so the loop widens with frequency (the
  // paper's Fig. 1, as a lag widens it), and W_i >= eps on all of [-max_rate, max_rate].
  if (play_cols_ > n_) lo.segment(n_, play_cols_ - n_).setConstant(0.0);
  // Preisach: densities >= 0, the reversible slope >= the least play slope (strictly rising).
  if (plane_) {
    lo.head(n_).setConstant(0.0);
    lo(n_) = s_.min_play_slope;
  }
  lo.segment(dz_col_, m_pos_ + m_neg_).setConstant(s_.min_dead_zone_slope);
  // Creep follows the move it answers: its lags' gains >= 0 (unbounded, lags longer than the
  // record, near each other, cancel in large opposite gains that drift away over a longer run).
  lo.segment(creep_col_, drift_col_ - creep_col_).setConstant(0.0);
  return lo;
}

Eigen::VectorXd Design::upper_bounds() const {
  return Eigen::VectorXd::Constant(unknowns_, kUnbounded);
}

void Design::add_penalty(Eigen::MatrixXd& gram) const {
  if (plane_ && s_.preisach_shape.empty()) {
    add_preisach_smoothness(gram, s_.preisach_cells, 0, s_.smoothness);
  }
}

namespace {
// The output dead zone S from the fitted cumulative weights of its inverse S' (w'_0 = 1, the
// increments of V outward from 0: `pos` above, `neg` below).
DeadZoneParameters output_map(const ModelStructure& s, const double* pos, std::size_t m_pos,
                              const double* neg, std::size_t m_neg) {
  DeadZoneParameters inv;
  inv.thresholds = s.dead_zone_thresholds;
  inv.weights.assign(inv.thresholds.size(), 0.0);
  const std::size_t zero = s.zero_index();
  inv.weights[zero] = 1.0;
  const auto up = cumulative_to_increments(pos, m_pos, 1.0);
  const auto down = cumulative_to_increments(neg, m_neg, 1.0);
  for (std::size_t j = 0; j < up.size(); ++j) inv.weights[zero + 1 + j] = up[j];
  for (std::size_t j = 0; j < down.size(); ++j) inv.weights[zero - 1 - j] = down[j];
  return DeadZoneSuperposition(std::move(inv)).inverse().parameters();
}
}  // namespace

std::unique_ptr<HysteresisModel> Design::build_plane(const Eigen::VectorXd& x) const {
  PreisachParameters p = plane_->parameters();
  if (s_.preisach_shape.empty()) {
    p.densities.assign(x.data(), x.data() + n_);
  } else {
    for (double& d : p.densities) d *= x[0];
  }
  p.slope = x[n_];
  p.offset = x[offset_col_] - s_.input_reference * p.slope;
  if (s_.has_dead_zones()) {
    p.output_map = output_map(s_, x.data() + dz_col_, static_cast<std::size_t>(m_pos_),
                              x.data() + dz_col_ + m_pos_, static_cast<std::size_t>(m_neg_));
  }
  p.center = s_.center;
  auto plane = std::make_unique<PreisachModel>(std::move(p));
  plane->set_sample_period(s_.dt);
  return plane;
}

std::unique_ptr<HysteresisModel> Design::build_hysteresis(const Eigen::VectorXd& x) const {
  if (plane_) return build_plane(x);
  const auto n = static_cast<std::size_t>(n_);
  // Signed rate law: W_i(rho) = U_i + (1 - rho) C_i, C_i = sum_{j<=i} e_j, so at rest U_i + C_i
  // and the rate coefficients -C_i per max_rate.
  const bool signed_law = s_.kind == ModelKind::kRateDependentPi && s_.rate_law == RateLaw::kSigned;
  Eigen::VectorXd rest = x.head(n_);
  Eigen::VectorXd rate_part = Eigen::VectorXd::Zero(n_);
  if (s_.kind == ModelKind::kRateDependentPi && !thresholds_law()) {
    rate_part = x.segment(n_, n_);
    if (signed_law) {
      for (Eigen::Index i = 1; i < n_; ++i) rate_part[i] += rate_part[i - 1];
      rest += rate_part;
      rate_part = -rate_part;
    }
  }
  PiParameters play;
  play.thresholds = s_.play_thresholds;
  play.weights = increments_ ? std::vector<double>(x.data(), x.data() + n)
                             : cumulative_to_increments(rest.data(), n);
  const double total = increments_ ? x.head(n_).sum() : rest[n_ - 1];
  play.offset = x[offset_col_] - s_.input_reference * total;
  if (!s_.has_dead_zones()) {
    if (s_.kind == ModelKind::kCoupledPlayPi) {
      CoupledPlayParameters p{cp_.r, cp_.ra, cp_.rb, cp_.rc, play.weights, play.offset, {}, 0.0};
      return std::make_unique<CoupledPlayPiModel>(std::move(p));
    }
    return std::make_unique<PiModel>(std::move(play));
  }
  play.offset += s_.center;
  // Inverse dead zone: w'_0 = 1 and increments of the cumulative V outward from 0.
  DeadZoneParameters forward = output_map(s_, x.data() + dz_col_, dz_pos_.size(),
                                          x.data() + dz_col_ + m_pos_, dz_neg_.size());
  if (s_.kind == ModelKind::kCoupledPlayPi) {
    CoupledPlayParameters p{
        cp_.r, cp_.ra, cp_.rb, cp_.rc, play.weights, play.offset, std::move(forward), s_.center};
    return std::make_unique<CoupledPlayPiModel>(std::move(p));
  }
  ModifiedPiParameters mpi{std::move(play), std::move(forward), s_.center};
  if (s_.kind == ModelKind::kModifiedPi) return std::make_unique<ModifiedPiModel>(std::move(mpi));
  // Rate-dependent: W_i(rate) = A_i + D_i rate / max_rate.
  RateDependentPiParameters rpi;
  rpi.base = std::move(mpi);
  rpi.rate_coefficients.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    rpi.rate_coefficients[i] = rate_part[k] * inv_max_rate_;
  }
  rpi.rate_law = s_.rate_law;
  if (thresholds_law()) {
    rpi.threshold_rate_s = s_.threshold_rate_s;
    rpi.threshold_rate_exponent = s_.threshold_rate_exponent;
  }
  rpi.max_rate = s_.max_rate;
  rpi.record_max_rate = s_.record_max_rate;
  rpi.rate_filter_s = s_.rate_filter_s;
  return std::make_unique<RateDependentPiModel>(std::move(rpi), s_.dt);
}

ActuatorModel Design::build(const Eigen::VectorXd& x) const {
  ActuatorModel model(build_hysteresis(x));
  if (!s_.creep_time_constants.empty()) {
    CreepParameters creep;
    creep.time_constants_s = s_.creep_time_constants;
    creep.gains.assign(x.data() + creep_col_, x.data() + drift_col_);
    model.set_creep(std::move(creep));
  }
  return model;
}

BoundedLsqResult fit_design(Design& design, std::span<const double> u, std::span<const double> y,
                            std::size_t begin, std::size_t end, std::size_t stride) {
  NormalEquations ne(design.unknowns());
  design.reset(u[0]);
  for (std::size_t k = 0; k < begin; ++k) design.skip(u[k]);
  if (stride <= 1) {
    for (std::size_t k = begin; k < end; ++k) ne.push(design.row(u[k], y[k], ne.row()));
  } else {
    for (std::size_t k = begin; k < end; ++k) {
      if ((k - begin) % stride == 0) {
        ne.push(design.row(u[k], y[k], ne.row()));
      } else {
        design.skip(u[k]);
      }
    }
  }
  return solve_design(design, ne);
}

BoundedLsqResult solve_design(const Design& design, NormalEquations& ne) {
  Eigen::MatrixXd g = ne.gram();
  design.add_penalty(g);
  return solve_bounded_lsq(g, ne.rhs(), design.lower_bounds(), design.upper_bounds());
}

}  // namespace hystbench::compensation::details
