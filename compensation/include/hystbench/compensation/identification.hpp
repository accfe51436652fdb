#pragma once
// Identification of PI-family models from a measured record (t, u, y).
// Not real-time: allocates, may take up to a few hundred ms for 1e5 samples at a fixed order
// (order selection and threshold refinement multiply that).
//
// Method: the weights enter every model linearly, so for fixed thresholds they are fitted by
// least squares on the whole record, with the cumulative weights (the slopes of the loading
// curve) bounded below by a small positive epsilon: the result is always invertible.
//   PI  : y = offset + sum_i w_i play_{r_i}(u), plays relaxed at u[0].
//   MPI : Kuhnen's error model, PI(u) = center + S'[y - center] with S' the inverse dead zone
//         (w'_0 = 1), then S = (S')^-1.
//   CPI : coupled plays with r_i uniform, ra/rb/rc = shared scales * r_i chosen on a grid.
//   RPI : MPI whose cumulative play weights are linear in |du/dt| (joint LS, or per-rate-group
//         fits regressed on rate; the one with the lower held-out error is kept).
// Thresholds may then be refined by Levenberg-Marquardt (variable projection), the model
// order is chosen by held-out error, a pure input delay and creep lags can be identified.
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/thresholds_rate_law.hpp"

namespace hystbench::compensation {

struct FitOptions {
  /// Model family; std::nullopt = "auto": the family with the lowest held-out error.
  std::optional<ModelKind> kind = ModelKind::kModifiedPi;
  /// Number of plays; 0 = chosen by held-out error.
  int operators = 0;
  /// Dead zones per side m (2m+1 dead-zone operators in all); -1 = chosen by held-out error.
  /// MPI and RPI; CPI too (its optional output stage; 0 = the coupled-play paper's model).
  int dead_zones = -1;
  /// Fraction of the record (at its end) kept out of the fit to measure held-out error.
  /// 0 = no held-out part (the order is then chosen on the fit error).
  double heldout_fraction = 0.25;
  /// Levenberg-Marquardt refinement of thresholds, kept only when held-out error improves.
  bool refine_thresholds = true;
  /// Smallest allowed cumulative weight, relative to the data's overall slope range/range
  /// (play weights) or to 1 (inverse dead-zone weights, which are dimensionless).
  double min_cumulative_weight = 1e-3;
  /// Optional progress callback: (fraction done 0..1, what is happening).
  std::function<void(double, const std::string&)> progress;

  /// Pure input delay in samples (ActuatorModel::set_delay); -1 = chosen among
  /// 0..max_delay_samples by held-out error (fit error without a held-out part).
  int delay_samples = -1;
  int max_delay_samples = 3;
  /// Samples at the start that are simulated but neither fitted nor scored (a start-up
  /// transient, e.g. the first cycle of a measurement that began from an unknown state).
  /// 0 (default) suits a record that starts relaxed at u[0] (the bench's recordings, which
  /// precondition the actuator first). std::nullopt = automatic, what `hystbench fit` uses for
  /// a file of unknown history: until the input has reached both of its extremes (the hysteresis
  /// memory of what came before is then wiped out), at most a quarter of the part before the
  /// held-out part. FitResult::skipped_samples says how many.
  std::optional<std::size_t> skip_samples = 0;
  /// Also try creep lags (CreepOperatorBank) fitted jointly with the weights; kept only when
  /// the held-out error improves (or always, with creep_always). Time constants:
  /// creep_time_constants_s, or when empty `creep_operators` log-spaced between 5 % and 50 % of
  /// the record duration.
  bool creep = false;
  bool creep_always = false;
  int creep_operators = 4;
  std::vector<double> creep_time_constants_s;
  /// Fit a straight-line drift of the output over the record (an earlier run's slow creep
  /// still settling, a sensor warming up) with the weights of every candidate, and score each
  /// with its drift added (extrapolated over the held-out part). The drift is the record's, not
  /// the model's: FitResult::drift_per_s reports the chosen model's, and every error is of the
  /// record without it. Exact for the classical PI; first order for the dead-zone families,
  /// whose error model drifts the hysteresis before the output dead zone.
  bool drift = false;
  /// The Preisach plane: also try relays whose thresholds widen with the input's rate (the
  /// thresholds law, preisach_model.hpp), fitted as the rate-dependent PI's is; kept only where
  /// the held-out error falls by more than 2 %.
  bool preisach_rate_law = true;
  /// With preisach_rate_law: this law (its widening, exponent, filter and caps) is refitted on
  /// the plane instead of searched for, and kept by the same rule (identify's neighbours of a
  /// plane whose law was found). Empty = searched.
  std::optional<ThresholdsRateLaw> preisach_given_rate_law;
  /// Fixed play thresholds (r_0 = 0, strictly increasing) [input unit]; overrides
  /// `operators` and disables their refinement. Empty = uniform on half the input span.
  std::vector<double> play_thresholds;
  /// Fixed thresholds of the INVERSE dead zone S' (MPI / RPI / CPI), on the output about `center`:
  /// strictly increasing with exactly one 0 [output unit]; overrides `dead_zones` and disables
  /// their refinement. Empty = 2m+1 thresholds uniform on the fitted output range.
  std::vector<double> dead_zone_thresholds;
  /// Dead-zone center [output unit]; default the middle of the fitted output range.
  std::optional<double> center;
  /// Units written to the model.
  Units units;
};

/// Score of one candidate model tried during the order / family search.
struct FitCandidate {
  ModelKind kind = ModelKind::kPi;
  int operators = 0;
  int dead_zones = 0;
  int delay_samples = 0;
  double fit_rmse = 0.0;
  double heldout_rmse = 0.0;
  std::string method;
};

struct FitResult {
  ActuatorModel model;
  ErrorStats fit;      ///< on the fitted part
  ErrorStats heldout;  ///< on the held-out part (simulated through from the start)
  std::size_t fit_samples = 0;
  std::size_t heldout_samples = 0;
  int operators = 0;
  int dead_zones = 0;
  std::string method;  ///< e.g. "constrained-lsq+lm"
  int delay_samples = 0;
  bool creep = false;
  std::size_t skipped_samples = 0;  ///< at the start, simulated but neither fitted nor scored
  double drift_per_s = 0.0;  ///< FitOptions::drift: the output drift taken off [output unit / s]
  /// What the fit decided that the user did not ask for, one sentence each (the start left out,
  /// a fall-back to the classical PI, creep kept or dropped).
  std::vector<std::string> notes;
  /// Every candidate scored, in the order tried (the chosen one is `model`).
  std::vector<FitCandidate> candidates;
};

/// Fits a model to a record. t [s] strictly increasing, u input, y output, equal lengths.
/// Sampling is taken as uniform with the mean step (t.back() - t.front()) / (N - 1).
/// Throws std::invalid_argument with a clear message for too few samples (< 50), constant
/// input or output, NaN/inf, mismatched lengths, non-increasing t or bad options.
FitResult fit_model(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                    const FitOptions& options = {});

/// fit_model() with `options.creep` forced on: hysteresis and creep lags fitted jointly
/// (creep kept only when it lowers the held-out error; FitResult::creep says whether it was).
FitResult fit_model_with_creep(std::span<const double> t, std::span<const double> u,
                               std::span<const double> y, FitOptions options = {});

/// Error statistics of `model` on a record, simulated from reset(u[0]) through the whole
/// record: `fit` on samples [skip, N - heldout), `heldout` on the last heldout_fraction * N.
struct ModelScore {
  ErrorStats fit;
  ErrorStats heldout;
};
ModelScore score_model(ActuatorModel model, std::span<const double> t, std::span<const double> u,
                       std::span<const double> y, double heldout_fraction,
                       std::size_t skip_samples = 0);

/// The classical-PI paper's triangular-matrix method (eq. 1-3) on one ascending branch
/// (u increasing from a major-loop minimum to the maximum): thresholds r_i = i*span/(2n)
/// and weights from the lower-triangular system. Offset so the branch start matches when the
/// plays are in the state the preceding descending branch leaves (p_i = u_min + r_i).
/// Throws std::invalid_argument for mismatched lengths, fewer than 2 samples, a branch that
/// is not non-decreasing or spans nothing, or operators < 1.
PiParameters identify_pi_triangular(std::span<const double> u_branch,
                                    std::span<const double> y_branch, int operators);

}  // namespace hystbench::compensation
