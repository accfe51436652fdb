#pragma once
// Linear-in-the-weights regressions of the PI family (identification internals).
// A ModelStructure holds everything that is fixed while the weights are fitted (thresholds,
// dead-zone thresholds, asymmetry scales, rate range, creep lags). A Design steps the
// operators over a record and writes one regressor row per sample; its unknowns are the
// CUMULATIVE weights, so invertibility constraints are plain lower bounds:
//   PI / CPI : y            = sum_i W_i (p_i - p_{i+1}) + c                      (p_n := u_ref)
//   CPI whose operators jump (rc > r or ra < rb): y = sum_i w_i (p_i - u_ref) + c with the
//              increments w_0 >= eps, w_i >= 0: a jump with a negative weight lowers the output
//   MPI      : S'[y - ctr]  = sum_i W_i (p_i - p_{i+1}) + c0   (Kuhnen's error model;
//              CPI with dead zones likewise, its coupled plays as the p_i)
//              with S' = inverse dead zone, w'_0 = 1, cumulative V_j >= eps outward from 0
//   RPI      : as MPI with W_i(rho) = A_i + D_i rho, rho = min(|rate|, max_rate) / max_rate,
//              A_i >= eps and D_i >= 0 (weights grow with rate; invertible on [0, max_rate]);
//              signed law: rho = clamp(rate / max_rate, -1, 1), W_i(rho) = U_i + (1 - rho) C_i
//              with U_i = W_i(+max_rate) >= eps and C_i = sum_{j<=i} e_j, each play's rate
//              slope -e_j <= 0 (the loop widens with rate, as with |du/dt|; invertible on
//              [-max_rate, max_rate]).
//              thresholds law: as MPI, every play's threshold r_i > 0 + threshold_rate_s * rate
//              (rate = min(|rate|, max_rate); with an exponent p < 1, + threshold_rate_s *
//              max_rate * |rho|^p); no rate columns.
//   Preisach : S'[y - ctr] = sum_c rho_c A_c(t) + s (u - u_ref) + c0 (S' only with dead zones;
//              without, y itself and ctr = 0): each cell's area in the up region A_c, its
//              density rho_c >= 0, the reversible slope s >= min_play_slope; a smoothness penalty
//              on neighbouring densities (add_penalty) with the structure's weight. With a
//              fixed shape, one column sum_c shape_c A_c(t) for all the cells, its scale >= 0.
//              With the thresholds law (rate_law kThresholds, threshold_rate_s > 0) the cells'
//              areas are those of the rate-widened front (preisach_model.hpp).
// Creep lags, when present, are extra unconstrained columns; so is the drift column (time from
// drift_t0_s), which estimates a record's slow drift and is no part of the built model.
#include <Eigen/Dense>
#include <array>
#include <memory>
#include <span>
#include <vector>

#include "details/constrained_lsq.hpp"
#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/dead_zone.hpp"
#include "hystbench/compensation/hysteresis_model.hpp"
#include "hystbench/compensation/preisach_model.hpp"
#include "hystbench/compensation/rate_estimator.hpp"

namespace hystbench::compensation::details {

struct ModelStructure {
  ModelKind kind = ModelKind::kPi;
  std::vector<double> play_thresholds;  ///< r_0 = 0 < r_1 < ... [input unit]
  /// Inverse dead-zone thresholds d' about `center`, strictly increasing with exactly one 0
  /// (MPI / RPI / CPI only; {0} alone = no dead zones) [output unit].
  std::vector<double> dead_zone_thresholds{0.0};
  double center = 0.0;           ///< [output unit] (with dead zones)
  double input_reference = 0.0;  ///< subtracted from the last play for conditioning (not RPI)
  std::array<double, 3> cp_scale{1.0, 1.0, 1.0};  ///< CPI: ra, rb, rc as multiples of r_i
  double max_rate = 0.0;                          ///< RPI: the rate law's cap [input unit / s]
  double record_max_rate = 0.0;  ///< RPI: the record's largest smooth rate [input unit / s]
  double rate_filter_s = 0.0;    ///< RPI: the rate's low-pass time constant (RateEstimator) [s]
  RateLaw rate_law = RateLaw::kMagnitude;  ///< RPI: du/dt or |du/dt|, on weights or thresholds
  double threshold_rate_s = 0.0;           ///< RPI thresholds law: widening per rate [s]
  double threshold_rate_exponent = 1.0;    ///< RPI thresholds law: the widening's power, (0, 1]
  double dt = 1e-3;                        ///< sample period [s]
  double min_play_slope = 0.0;             ///< lower bound on cumulative play weights
  double min_dead_zone_slope = 0.0;        ///< lower bound on cumulative inverse dead-zone weights
  std::vector<double> creep_time_constants;  ///< creep lag columns [s] (empty = none)
  bool drift = false;              ///< a drift column: time since sample 0 less drift_t0_s [s]
  double drift_t0_s = 0.0;         ///< the time the drift column is zero at [s]
  std::size_t preisach_cells = 0;  ///< Preisach: cells per side of the plane
  double plane_min = 0.0, plane_max = 0.0;  ///< Preisach: the plane's input range [input unit]
  double smoothness = 0.0;  ///< Preisach: the penalty's weight (add_preisach_smoothness)
  /// Preisach: the densities' shape, fixed (PreisachParameters::densities): then one column, the
  /// plane's output, whose scale is fitted. Empty: every cell's density is an unknown.
  std::vector<double> preisach_shape;

  bool operator==(const ModelStructure&) const = default;
  std::size_t plays() const noexcept { return play_thresholds.size(); }
  /// The drift column's value at sample k: its time from drift_t0_s [s].
  double drift_time_s(std::size_t k) const noexcept {
    return static_cast<double>(k) * dt - drift_t0_s;
  }
  std::size_t zero_index() const;  ///< index of 0 in dead_zone_thresholds
  /// The thresholds law its fields hold (rate_law kThresholds; a plane's or an rpi's).
  ThresholdsRateLaw thresholds_law() const noexcept {
    return {threshold_rate_s, threshold_rate_exponent, max_rate, record_max_rate, rate_filter_s};
  }
  /// Sets rate_law to kThresholds and its fields from `law`.
  void set_thresholds_law(const ThresholdsRateLaw& law) noexcept {
    rate_law = RateLaw::kThresholds;
    threshold_rate_s = law.threshold_rate_s;
    threshold_rate_exponent = law.exponent;
    max_rate = law.max_rate;
    record_max_rate = law.record_max_rate;
    rate_filter_s = law.rate_filter_s;
  }
  /// MPI and RPI always have the dead-zone stage; CPI and Preisach when they have dead zones ({0}
  /// alone: none).
  bool has_dead_zones() const noexcept {
    return kind == ModelKind::kModifiedPi || kind == ModelKind::kRateDependentPi ||
           ((kind == ModelKind::kCoupledPlayPi || kind == ModelKind::kPreisach) &&
            dead_zone_thresholds.size() > 1);
  }
};

/// Adds the drift line per_s * s.drift_time_s(k) to every y[k] (a fitted drift to a model's
/// simulated output; -per_s takes it off a record).
void add_drift(const ModelStructure& s, double per_s, std::span<double> y) noexcept;

/// The coupled-play thresholds (r, ra, rb, rc) of a structure.
struct CoupledThresholds {
  std::vector<double> r, ra, rb, rc;
};
CoupledThresholds coupled_thresholds(const ModelStructure& s);

/// The rate of every sample (first sample 0) as a rate-dependent model with this rate filter
/// sees it, before its cap at max_rate (estimate_rates).
std::vector<double> sample_rates(std::span<const double> u, double dt, double rate_filter_s = 0.0);

class Design {
 public:
  explicit Design(ModelStructure s);

  const ModelStructure& structure() const noexcept { return s_; }
  Eigen::Index unknowns() const noexcept { return unknowns_; }
  Eigen::Index plays() const noexcept { return n_; }
  Eigen::Index offset_column() const noexcept { return offset_col_; }
  Eigen::Index dead_zone_column() const noexcept { return dz_col_; }
  Eigen::Index dead_zone_unknowns() const noexcept { return m_pos_ + m_neg_; }
  Eigen::Index creep_column() const noexcept { return creep_col_; }
  /// The drift column (ModelStructure::drift), its coefficient in output unit per second.
  Eigen::Index drift_column() const noexcept { return drift_col_; }
  /// True when the play unknowns are the weights themselves, not their cumulative sums.
  bool increment_weights() const noexcept { return increments_; }

  void reset(double u0) noexcept;
  /// Steps the operators with input u (measured output y) and writes the regressors of this
  /// sample to a[0 .. unknowns()); returns the regression target.
  double row(double u, double y, double* a) noexcept { return step(u, y, a); }
  /// Steps the operators with input u as row() does, without the regressors: a sample the fit
  /// leaves out (the rows after it are the same as when row() stepped it).
  void skip(double u) noexcept { (void)step(u, 0.0, nullptr); }
  /// Makes the next row() or skip() the record's sample k (the drift column's clock), for a
  /// record stepped on some of its samples only.
  void set_sample(std::size_t k) noexcept { sample_ = k; }

  Eigen::VectorXd lower_bounds() const;
  Eigen::VectorXd upper_bounds() const;
  /// Adds the structure's penalty to a Gram matrix over unknowns() (Preisach: the smoothness of
  /// its densities; nothing for the play families).
  void add_penalty(Eigen::MatrixXd& gram) const;

  /// The model for the fitted unknowns (hysteresis + creep gains; no delay, not configured).
  ActuatorModel build(const Eigen::VectorXd& x) const;
  /// The hysteresis of build() only.
  std::unique_ptr<HysteresisModel> build_hysteresis(const Eigen::VectorXd& x) const;

 private:
  std::unique_ptr<HysteresisModel> build_plane(const Eigen::VectorXd& x) const;
  /// Steps the plays with input u; `widen` is added to every threshold [input unit].
  void step_operators(double u, double widen) noexcept;
  /// skip()'s part after the plays: the plane's relays, the creep lags, the sample count.
  void step_relays_and_lags(double u) noexcept;
  /// row(), or skip() for a null `a`.
  double step(double u, double y, double* a) noexcept;
  bool thresholds_law() const noexcept {
    return s_.kind == ModelKind::kRateDependentPi && s_.rate_law == RateLaw::kThresholds;
  }

  ModelStructure s_;
  CoupledThresholds cp_;
  std::unique_ptr<PreisachModel> plane_;  // Preisach: the grid that gives the cells' areas
  Eigen::Index n_ = 0;                    // plays
  Eigen::Index m_pos_ = 0;                // dead zones above 0
  Eigen::Index m_neg_ = 0;                // dead zones below 0
  Eigen::Index play_cols_ = 0;
  Eigen::Index offset_col_ = 0;
  Eigen::Index dz_col_ = 0;
  Eigen::Index creep_col_ = 0;
  Eigen::Index drift_col_ = 0;
  Eigen::Index unknowns_ = 0;
  std::size_t sample_ = 0;               // rows since reset (the drift column's clock)
  bool increments_ = false;              // CPI with jumps: unknowns are w_i, not W_i
  std::vector<double> z_;                // operator outputs
  std::vector<double> creep_a_;          // lag poles
  std::vector<double> creep_x_;          // lag states
  std::vector<double> dz_pos_, dz_neg_;  // thresholds outward from 0
  double u_prev_ = 0.0;
  double inv_max_rate_ = 0.0;
  RateEstimator rate_;
};

/// Fits the design's unknowns on rows [begin, end) of the record (the operators are stepped
/// from reset(u[0]) at sample 0, so rows before `begin` only advance the state). With
/// stride > 1 only every stride-th row of [begin, end) enters the fit (the operators still see
/// every sample): a cheaper, slightly noisier fit for searches.
BoundedLsqResult fit_design(Design& design, std::span<const double> u, std::span<const double> y,
                            std::size_t begin, std::size_t end, std::size_t stride = 1);

/// The design's unknowns from the normal equations of its rows: its penalty added, bounded to
/// its limits.
BoundedLsqResult solve_design(const Design& design, NormalEquations& ne);

}  // namespace hystbench::compensation::details
