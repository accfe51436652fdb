#include "diagnosis/details/extension_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "details/diagnosis_signals.hpp"
#include "details/scoped_no_denormals.hpp"
#include "details/second_order_bank.hpp"
#include "diagnosis/details/cancel_point.hpp"
#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/delay_line.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/preisach_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"

namespace hystbench::compensation::details {

namespace {

constexpr double kMinCumulativeWeight = 1e-3;  // as FitOptions::min_cumulative_weight

// Piecewise-linear drift basis: knots every `spacing` samples, knot 0 left out (the offset
// column carries the level there). Writes the `knots` values for sample k. Before `origin` (the
// record's unscored start, which no fitted row constrains) the drift holds its value there.
class DriftBasis {
 public:
  DriftBasis(std::size_t block, std::size_t knots, std::size_t origin)
      : block_(static_cast<double>(block)), knots_(knots), origin_(origin) {}
  std::size_t size() const noexcept { return knots_; }
  void row(std::size_t k, double* a) const noexcept {
    std::fill(a, a + knots_, 0.0);
    const double x =
        std::min(static_cast<double>(std::max(k, origin_)) / block_, static_cast<double>(knots_));
    const auto i = static_cast<std::size_t>(x);
    const double frac = x - static_cast<double>(i);
    if (i >= 1) a[i - 1] += 1.0 - frac;
    if (i < knots_ && frac > 0.0) a[i] += frac;
  }

 private:
  double block_;
  std::size_t knots_;
  std::size_t origin_;
};

}  // namespace

std::vector<double> delayed(std::span<const double> u, double d) {
  std::vector<double> out(u.size());
  if (u.empty()) return out;
  DelayLine line = DelayLine::of(d);
  line.reset(u[0]);
  for (std::size_t k = 0; k < u.size(); ++k) out[k] = line.push(u[k]);
  return out;
}

ModelStructure pi_structure(const DiagnosisRecord& r, int plays) {
  ModelStructure s;
  s.kind = ModelKind::kPi;
  s.dt = r.dt;
  const double u_span = r.u_hi - r.u_lo;
  s.play_thresholds = uniform_thresholds(static_cast<std::size_t>(plays), 0.5 * u_span);
  s.input_reference = 0.5 * (r.u_lo + r.u_hi);
  s.min_play_slope = kMinCumulativeWeight * (r.y_hi - r.y_lo) / u_span;
  s.min_dead_zone_slope = kMinCumulativeWeight;
  s.center = 0.5 * (r.y_lo + r.y_hi);
  return s;
}

std::optional<ModelStructure> structure_of(const ActuatorModel& model, const DiagnosisRecord& r) {
  if (!model.valid()) return std::nullopt;
  ModelStructure s = pi_structure(r, 1);
  const HysteresisModel& h = model.hysteresis();
  s.kind = h.kind();
  auto set_dead_zones = [&s](const ModifiedPiParameters& p) {
    s.play_thresholds = p.play.thresholds;
    s.center = p.center;
    s.dead_zone_thresholds = DeadZoneSuperposition(p.dead_zone).inverse().parameters().thresholds;
  };
  try {
    switch (h.kind()) {
      case ModelKind::kPi:
        s.play_thresholds = dynamic_cast<const PiModel&>(h).parameters().thresholds;
        break;
      case ModelKind::kModifiedPi:
        set_dead_zones(dynamic_cast<const ModifiedPiModel&>(h).parameters());
        break;
      case ModelKind::kRateDependentPi: {
        const auto& p = dynamic_cast<const RateDependentPiModel&>(h).parameters();
        set_dead_zones(p.base);
        s.max_rate = p.max_rate;
        s.rate_filter_s = p.rate_filter_s;
        s.rate_law = p.rate_law;
        s.threshold_rate_s = p.threshold_rate_s;
        s.threshold_rate_exponent = p.threshold_rate_exponent;
        if (!(s.max_rate > 0.0)) return std::nullopt;
        break;
      }
      case ModelKind::kPreisach: {
        const auto& p = dynamic_cast<const PreisachModel&>(h).parameters();
        s.play_thresholds.clear();
        s.preisach_cells = p.cells;
        s.plane_min = p.u_min;
        s.plane_max = p.u_max;
        s.preisach_shape = p.densities;
        s.center = p.center;
        if (p.rate_law.active()) s.set_thresholds_law(p.rate_law);
        if (p.output_map.thresholds.size() > 1) {
          s.dead_zone_thresholds =
              DeadZoneSuperposition(p.output_map).inverse().parameters().thresholds;
        }
        break;
      }
      case ModelKind::kCoupledPlayPi: {
        const auto& p = dynamic_cast<const CoupledPlayPiModel&>(h).parameters();
        s.play_thresholds = p.r;
        std::vector<double> ka, kb, kc;
        for (std::size_t i = 0; i < p.r.size(); ++i) {
          if (p.r[i] <= 0.0) continue;
          ka.push_back(p.ra[i] / p.r[i]);
          kb.push_back(p.rb[i] / p.r[i]);
          kc.push_back(p.rc[i] / p.r[i]);
        }
        s.cp_scale = {median(ka, 1.0), median(kb, 1.0), median(kc, 1.0)};
        if (p.has_dead_zones()) {
          s.center = p.center;
          s.dead_zone_thresholds =
              DeadZoneSuperposition(p.dead_zone).inverse().parameters().thresholds;
        }
        break;
      }
    }
  } catch (const DiagnosisCancelled&) {
    throw;
  } catch (const std::exception&) {
    return std::nullopt;  // e.g. a dead zone that cannot be inverted
  }
  if (s.play_thresholds.empty() && s.kind != ModelKind::kPreisach) return std::nullopt;
  if (model.creep()) s.creep_time_constants = model.creep()->time_constants_s;
  return s;
}

namespace {

// A spec's linear unknowns fitted jointly to target y: the model (configured at the record's dt,
// delay set) and the drift curve.
struct Joint {
  ActuatorModel model;
  std::vector<double> drift;
  double regression_mse = 0.0;
};

// The dynamics applied to the regressor columns that pass through them: plays (and rate
// columns), creep lags. The offset is constant (unit DC gain keeps it) and the dead-zone columns
// act on the measured output.
class FilteredColumns {
 public:
  FilteredColumns(const Design& design, const std::optional<DynamicsParameters>& dynamics,
                  double dt)
      : columns_{Columns{0, static_cast<std::size_t>(design.offset_column())},
                 Columns{static_cast<std::size_t>(design.creep_column()),
                         static_cast<std::size_t>(design.unknowns() - design.creep_column())}} {
    if (dynamics) {
      bank_.emplace(SecondOrderDynamics(*dynamics, dt), columns_[0].count + columns_[1].count);
    }
  }
  bool active() const noexcept { return bank_.has_value(); }
  /// Sample k's row through the dynamics into `a` (the filtered columns only; `row` may be `a`);
  /// sample 0 settles them at its values. Nothing without dynamics.
  void apply(std::size_t k, const double* row, double* a) noexcept {
    if (!bank_) return;
    std::size_t signal = 0;
    for (const Columns& c : columns_) {
      if (k == 0) bank_->reset(signal, row + c.first, c.count);
      bank_->step(signal, row + c.first, a + c.first, c.count);
      signal += c.count;
    }
  }

 private:
  struct Columns {
    std::size_t first, count;
  };
  std::array<Columns, 2> columns_;
  std::optional<SecondOrderBank> bank_;
};

// A free Preisach plane's fit takes every stride-th fit row where the record holds more than this
// many per unknown: its hundreds of cells make each row's update costly, and neighbouring rows of
// a fast record (identify's at 10 kHz) add little.
constexpr std::size_t kPlaneRowsPerUnknown = 200;

std::size_t row_stride(const DiagnosisRecord& r, const ExtensionSpec& spec, Eigen::Index unknowns,
                       FitRows rows) {
  const std::size_t stride = rows == FitRows::kSearch ? r.search_stride : 1;
  const ModelStructure& s = spec.structure;
  if (s.kind != ModelKind::kPreisach || !s.preisach_shape.empty()) return stride;
  const std::size_t enough = kPlaneRowsPerUnknown * static_cast<std::size_t>(unknowns);
  return std::max(stride, r.split.fit_samples / std::max<std::size_t>(1, enough));
}

Joint fit_joint(const DiagnosisRecord& r, std::span<const double> y, const ExtensionSpec& spec,
                FitRows rows, const DesignRows* cached) {
  Design design(spec.structure);
  const Eigen::Index nd = design.unknowns();
  const DriftBasis drift(r.drift_knot_samples(), spec.drift ? r.drift_knots() : 0,
                         r.drift_origin());
  const auto nb = static_cast<Eigen::Index>(drift.size());
  const Eigen::Index unknowns = nd + nb;
  const std::vector<double> ud = delayed(r.u, spec.delay_samples);

  FilteredColumns filters(design, spec.dynamics, r.dt);

  // Rate-dependent rows above the model's rate cap (input steps) are not fitted: the model
  // caps the rate there, the design does not.
  const bool rate_cap = spec.structure.kind == ModelKind::kRateDependentPi;
  const double max_step = spec.structure.max_rate * r.dt;

  const std::size_t stride = row_stride(r, spec, unknowns, rows);
  NormalEquations ne(unknowns);
  std::vector<double> scratch(static_cast<std::size_t>(unknowns));
  design.reset(ud[0]);
  EveryNth fit_rows(stride);
  for (std::size_t k = 0; k < r.n; ++k) {
    bool use = r.fit_row(k) && fit_rows.take();
    if (use && rate_cap && k > 0 && std::abs(ud[k] - ud[k - 1]) > max_step) use = false;
    if (!use && !filters.active()) {
      // Nothing reads the row: the operators step alone (a cached row is not needed at all).
      if (cached == nullptr) design.skip(ud[k]);
      continue;
    }
    double* a = use ? ne.row() : scratch.data();
    // The row: cached (copied only where it is used; the filters read it in place) or stepped.
    const double* row = a;
    double target = 0.0;
    if (cached != nullptr) {
      row = cached->row(k);
      if (use) std::copy_n(row, nd, a);
      target = cached->target(k);
    } else {
      target = design.row(ud[k], y[k], a);
    }
    filters.apply(k, row, a);
    if (use && nb > 0) drift.row(k, a + nd);  // only a fitted row reads its drift
    if (use) ne.push(target);
  }
  Eigen::VectorXd lo(unknowns), hi(unknowns);
  lo.head(nd) = design.lower_bounds();
  hi.head(nd) = design.upper_bounds();
  lo.tail(nb).setConstant(-std::numeric_limits<double>::infinity());
  hi.tail(nb).setConstant(std::numeric_limits<double>::infinity());
  const Eigen::MatrixXd& G = ne.gram();
  const Eigen::VectorXd& b = ne.rhs();
  Eigen::MatrixXd penalised = G;
  design.add_penalty(penalised);
  const Eigen::VectorXd x = solve_bounded_lsq(penalised, b, lo, hi).x;
  const double rss = ne.target_square_sum() - 2.0 * b.dot(x) + x.dot(G * x);

  Joint out;
  out.regression_mse =
      std::max(rss, 0.0) / static_cast<double>(std::max<Eigen::Index>(1, ne.rows()));
  out.model = design.build(x.head(nd));
  if (spec.dynamics) out.model.set_dynamics(*spec.dynamics);
  out.model.configure(r.dt);
  out.model.set_delay(spec.delay_samples * r.dt);
  if (nb > 0) {
    out.drift.resize(r.n);
    std::vector<double> a(drift.size());
    for (std::size_t k = 0; k < r.n; ++k) {
      drift.row(k, a.data());
      double d = 0.0;
      for (Eigen::Index m = 0; m < nb; ++m) d += a[static_cast<std::size_t>(m)] * x[nd + m];
      out.drift[k] = d;
    }
  }
  return out;
}

// The additive terms' coefficients from their equations: nc creep lags' gains, then nb drift
// pieces.
Eigen::VectorXd additive_coefficients(NormalEquations& ne, std::size_t nc, std::size_t nb) {
  const auto c = static_cast<Eigen::Index>(nc), b = static_cast<Eigen::Index>(nb);
  const Eigen::VectorXd inf =
      Eigen::VectorXd::Constant(c + b, std::numeric_limits<double>::infinity());
  if (nc > 0 && nb > 0) {
    // Creep first, then the drift on what it leaves: lags longer than the record are near
    // ramps, as the drift's pieces are, and fitted together the two cancel in large opposite
    // gains that a record without this drift then shows. Creep is the device's, the drift
    // what its input does not explain.
    Eigen::VectorXd coef(c + b);
    const Eigen::MatrixXd& g = ne.gram();
    coef.head(c) = solve_bounded_lsq(g.topLeftCorner(c, c), ne.rhs().head(c),
                                     Eigen::VectorXd::Zero(c), inf.head(c))
                       .x;
    coef.tail(b) = solve_bounded_lsq(g.bottomRightCorner(b, b),
                                     ne.rhs().tail(b) - g.bottomLeftCorner(b, c) * coef.head(c),
                                     -inf.tail(b), inf.tail(b))
                       .x;
    return coef;
  }
  // Creep follows the move it answers, its lags' gains >= 0: unbounded, lags longer than the
  // record (near ramps, near each other) cancel in large opposite gains that drift away over a
  // longer run. The drift's pieces are free.
  Eigen::VectorXd lo = -inf;
  lo.head(c).setZero();
  return solve_bounded_lsq(ne.gram(), ne.rhs(), lo, inf).x;
}

// The spec without the additive terms an alternating fit holds apart.
ExtensionSpec hysteresis_only(ExtensionSpec spec) {
  spec.structure.creep_time_constants.clear();
  spec.drift = false;
  return spec;
}

// Dead-zone kinds regress S'[y] (Kuhnen's error model), where creep and drift, which add to the
// output, do not belong. As the identification does for creep, alternate: the hysteresis on
// y minus the additive terms, then the additive terms (creep gains, drift) on y minus the
// simulated hysteresis, both linear.
// `hysteresis_target`, when given, gets the output less the additive terms last fitted.
Joint fit_alternating(const DiagnosisRecord& r, const ExtensionSpec& spec, FitRows rows,
                      std::vector<double>* hysteresis_target = nullptr) {
  const ExtensionSpec hysteresis = hysteresis_only(spec);
  const std::vector<double>& taus = spec.structure.creep_time_constants;
  const DriftBasis drift(r.drift_knot_samples(), spec.drift ? r.drift_knots() : 0,
                         r.drift_origin());
  const std::size_t nc = taus.size(), nb = drift.size(), unknowns = nc + nb;
  // Unit-gain creep lag states of the delayed input, as the model's bank steps them.
  const std::vector<double> ud = delayed(r.u, spec.delay_samples);
  std::vector<std::vector<double>> lags(nc, std::vector<double>(r.n));
  for (std::size_t j = 0; j < nc; ++j) {
    const double a = std::exp(-r.dt / taus[j]);
    double x = ud[0];
    for (std::size_t k = 0; k < r.n; ++k) lags[j][k] = x = a * x + (1.0 - a) * ud[k];
  }
  const std::size_t stride = rows == FitRows::kSearch ? r.search_stride : 1;
  std::vector<double> target(r.y.begin(), r.y.end());
  std::vector<double> additive(r.n, 0.0);
  Joint out;
  Eigen::VectorXd coef = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(unknowns));
  std::vector<double> a(unknowns);
  for (int iteration = 0; iteration < 4; ++iteration) {
    diagnosis::cancellation_point();
    out = fit_joint(r, target, hysteresis, rows, nullptr);
    const std::vector<double> h = ActuatorModel(out.model).simulate(r.u, r.dt);
    NormalEquations ne(static_cast<Eigen::Index>(unknowns));
    EveryNth fit_rows(stride);
    for (std::size_t k = 0; k < r.n; ++k) {
      if (!r.fit_row(k) || !fit_rows.take()) continue;
      double* row = ne.row();
      for (std::size_t j = 0; j < nc; ++j) row[j] = lags[j][k];
      drift.row(k, row + nc);
      ne.push(r.y[k] - h[k]);
    }
    coef = additive_coefficients(ne, nc, nb);
    const double rss =
        ne.target_square_sum() - 2.0 * ne.rhs().dot(coef) + coef.dot(ne.gram() * coef);
    out.regression_mse =
        std::max(rss, 0.0) / static_cast<double>(std::max<Eigen::Index>(1, ne.rows()));
    for (std::size_t k = 0; k < r.n; ++k) {
      double v = 0.0;
      for (std::size_t j = 0; j < nc; ++j) v += coef[static_cast<Eigen::Index>(j)] * lags[j][k];
      drift.row(k, a.data());
      for (std::size_t m = 0; m < nb; ++m) v += coef[static_cast<Eigen::Index>(nc + m)] * a[m];
      target[k] = r.y[k] - v;
    }
  }
  if (hysteresis_target != nullptr) *hysteresis_target = target;
  if (nc > 0) {
    out.model.set_creep(CreepParameters{taus, std::vector<double>(coef.data(), coef.data() + nc)});
  }
  if (nb > 0) {
    out.drift.assign(r.n, 0.0);
    for (std::size_t k = 0; k < r.n; ++k) {
      drift.row(k, a.data());
      for (std::size_t m = 0; m < nb; ++m) {
        out.drift[k] += coef[static_cast<Eigen::Index>(nc + m)] * a[m];
      }
    }
  }
  return out;
}

}  // namespace

bool alternates(const ExtensionSpec& spec) noexcept {
  const bool additive = !spec.structure.creep_time_constants.empty() || spec.drift;
  return spec.structure.has_dead_zones() && additive;
}

DesignRows::DesignRows(const DiagnosisRecord& r, const ExtensionSpec& spec)
    : DesignRows(r, spec, r.y) {}

DesignRows::DesignRows(const DiagnosisRecord& r, const ExtensionSpec& spec,
                       std::span<const double> y)
    : record_(&r), spec_(spec), measured_(y.data() == r.y.data()) {
  if (alternates(spec)) return;  // never served
  Design design(spec.structure);
  columns_ = static_cast<std::size_t>(design.unknowns());
  rows_.resize(r.n * columns_);
  targets_.resize(r.n);
  const std::vector<double> ud = delayed(r.u, spec.delay_samples);
  design.reset(ud[0]);
  for (std::size_t k = 0; k < r.n; ++k) {
    targets_[k] = design.row(ud[k], y[k], rows_.data() + k * columns_);
  }
}

bool DesignRows::serves(const DiagnosisRecord& r, const ExtensionSpec& spec) const noexcept {
  return columns_ > 0 && measured_ && &r == record_ && spec.structure == spec_.structure &&
         spec.delay_samples == spec_.delay_samples && !alternates(spec);
}

namespace {

// One turn of the alternation: `spec`'s hysteresis fitted on `held` (the output less the held
// creep and drift); `rows`, when given, its design stepped against `held`.
double held_turn_mse(const DiagnosisRecord& r, const ExtensionSpec& spec,
                     std::span<const double> held, const DesignRows* rows) {
  const ScopedNoDenormals flushed;
  diagnosis::cancellation_point();
  return fit_joint(r, held, hysteresis_only(spec), FitRows::kSearch, rows).regression_mse;
}

}  // namespace

std::vector<double> held_search_target(const DiagnosisRecord& r, const ExtensionSpec& spec) {
  std::vector<double> target;
  if (alternates(spec)) fit_alternating(r, spec, FitRows::kSearch, &target);
  return target;
}

double search_mse(const DiagnosisRecord& r, const ExtensionSpec& spec, std::span<const double> held,
                  const DesignRows* cached) {
  if (held.empty() || !alternates(spec)) {
    if (cached != nullptr && !cached->serves(r, spec)) cached = nullptr;
    return fit_extension(r, spec, FitRows::kSearch, false, cached).regression_mse;
  }
  return held_turn_mse(r, spec, held, nullptr);
}

DynamicsSearch::DynamicsSearch(const DiagnosisRecord& r, const ExtensionSpec& spec)
    : r_(r),
      spec_(spec),
      held_(held_search_target(r, spec)),
      rows_(r, held_.empty() ? spec : hysteresis_only(spec),
            held_.empty() ? r.y : std::span<const double>(held_)) {}

double DynamicsSearch::operator()(double fn, double zeta) const {
  ExtensionSpec spec = spec_;
  spec.dynamics = DynamicsParameters{fn, zeta};
  return held_.empty() ? search_mse(r_, spec, held_, &rows_)
                       : held_turn_mse(r_, spec, held_, &rows_);
}

ExtensionFit fit_extension(const DiagnosisRecord& r, const ExtensionSpec& spec, FitRows rows,
                           bool predict, const DesignRows* cached) {
  // The dynamics filter regressor columns that go quiet; their states decay through the
  // subnormal range for thousands of samples, where arithmetic is slow (ScopedNoDenormals).
  const ScopedNoDenormals flushed;
  diagnosis::cancellation_point();
  if (cached != nullptr && !cached->serves(r, spec)) cached = nullptr;
  Joint j =
      alternates(spec) ? fit_alternating(r, spec, rows) : fit_joint(r, r.y, spec, rows, cached);
  ExtensionFit out;
  out.spec = spec;
  out.model = std::move(j.model);
  out.model.units = r.units;
  out.model.input_min = r.u_lo;
  out.model.input_max = r.u_hi;
  out.drift = std::move(j.drift);
  out.regression_mse = j.regression_mse;
  if (predict) {
    ActuatorModel sim(out.model);
    out.prediction = sim.simulate(r.u, r.dt);
    for (std::size_t k = 0; k < out.drift.size(); ++k) out.prediction[k] += out.drift[k];
    const SplitErrors e = split_errors(r, out.prediction);
    out.fit = e.fit;
    out.heldout = e.heldout;
  }
  return out;
}

}  // namespace hystbench::compensation::details
