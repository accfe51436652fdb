#pragma once
// Extended-model fits of the diagnosis (internals). An ExtensionSpec is a PI-family structure
// (designs.hpp, creep lags included) plus any of: a pure input delay, second-order dynamics
// after the hysteresis and creep, and a drift piecewise linear in time. For a fixed spec every
// unknown enters linearly:
//   y(k) = D[ sum_i W_i q_i(u(k - d)) + c + sum_j g_j x_j(u(k - d)) ](k) + sum_m b_m hat_m(k)
// (D linear with unit DC gain, so it filters each regressor column), and all are fitted
// together by the identification's bounded least squares on the FIT rows of the record only;
// the operators are stepped through every sample. For dead-zone kinds (MPI / RPI) the
// dynamics and drift are approximations (Kuhnen's error model regresses S'[y]).
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "details/designs.hpp"
#include "diagnosis/details/record.hpp"
#include "hystbench/compensation/second_order_dynamics.hpp"

namespace hystbench::compensation::details {

struct ExtensionSpec {
  ModelStructure structure;
  double delay_samples = 0.0;  ///< >= 0; a fraction interpolates the input (DelayLine)
  std::optional<DynamicsParameters> dynamics;
  bool drift = false;  ///< hat functions with knots at the split's block edges
};

struct ExtensionFit {
  ExtensionSpec spec;
  ActuatorModel model;             ///< configured at the record's dt, delay set, no drift
  std::vector<double> drift;       ///< fitted drift per sample (empty without drift)
  std::vector<double> prediction;  ///< model output + drift, whole record (empty if !predict)
  ErrorStats fit, heldout;         ///< of `prediction` (when predicted)
  double regression_mse = 0.0;     ///< mean square regression residual on the rows used
};

enum class FitRows {
  kAll,     ///< every fit row
  kSearch,  ///< every record.search_stride-th fit row (cheaper, for searches)
};

/// True when the spec's fit alternates: dead zones regress S'[y], where creep and drift, which
/// add to the output, do not belong, so the hysteresis and those additive terms are fitted in
/// turn over a moving target.
bool alternates(const ExtensionSpec& spec) noexcept;

/// A spec's design rows and regression targets through the whole record, stepped once: the fits
/// of a search that varies only the dynamics filter these instead of stepping the operators again
/// (the same arithmetic, so the same fits). Holds record samples x design unknowns doubles.
class DesignRows {
 public:
  /// Steps the spec's design (its structure at its delay; the dynamics and drift are not part of
  /// it) through the record against its measured output; nothing for a spec it cannot serve.
  DesignRows(const DiagnosisRecord& r, const ExtensionSpec& spec);
  /// The same against `y` (r.n samples) instead of the measured output: rows no fit_extension
  /// takes (serves() is false), for DynamicsSearch.
  DesignRows(const DiagnosisRecord& r, const ExtensionSpec& spec, std::span<const double> y);
  /// True when fits of `spec` on `r` may use these rows: stepped against the measured output,
  /// the same structure and delay, fitted in one pass (not alternating).
  bool serves(const DiagnosisRecord& r, const ExtensionSpec& spec) const noexcept;
  /// Sample k's row (`columns()` values) and target.
  const double* row(std::size_t k) const noexcept { return rows_.data() + k * columns_; }
  double target(std::size_t k) const noexcept { return targets_[k]; }
  std::size_t columns() const noexcept { return columns_; }

 private:
  const DiagnosisRecord* record_;
  ExtensionSpec spec_;
  std::size_t columns_ = 0;  ///< 0 when not stepped (a spec it cannot serve)
  bool measured_ = true;     ///< stepped against the record's measured output
  std::vector<double> rows_, targets_;
};

/// Fits the spec's linear unknowns; with `predict` also simulates the model through the record
/// and scores it on both parts. For PI / CPI kinds regression_mse is the output error on the
/// rows used, so searches over delay and dynamics can skip the simulation. `cached` rows, when
/// given and they serve the spec, stand for stepping its design.
ExtensionFit fit_extension(const DiagnosisRecord& r, const ExtensionSpec& spec,
                           FitRows rows = FitRows::kAll, bool predict = true,
                           const DesignRows* cached = nullptr);

/// Searches rank many specs that differ in one part (a mode, a rate law) by their regression
/// error on every search_stride-th fit row, without simulating. Where a spec alternates, a full
/// fit per trial simulates the model through the record four times; a search instead holds the
/// creep and drift at their alternating fit of the spec it starts from and fits each trial's
/// hysteresis on the output less them (one step of the alternation). The fits a search's result
/// goes to (fit_extension) alternate in full. Not real-time.
///
/// The output less the creep and drift of `spec`'s alternating fit, which the searches from it
/// regress; empty where `spec` does not alternate (they regress the output).
std::vector<double> held_search_target(const DiagnosisRecord& r, const ExtensionSpec& spec);

/// A search trial's mean square regression residual: `spec` (its creep and drift those of the
/// spec `held` came from) fitted on `held`, or as fit_extension does (with `cached` where those
/// rows serve it) where `held` is empty or `spec` does not alternate.
double search_mse(const DiagnosisRecord& r, const ExtensionSpec& spec, std::span<const double> held,
                  const DesignRows* cached = nullptr);

/// The regression error of a spec as a function of its dynamics alone, for the resonance
/// searches (variable projection: every other unknown is linear for a fixed mode): the design is
/// stepped once, each evaluation filters its rows and solves (search_mse, creep and drift held
/// where the spec alternates).
class DynamicsSearch {
 public:
  DynamicsSearch(const DiagnosisRecord& r, const ExtensionSpec& spec);
  /// search_mse with the mode (fn [Hz], zeta) in place of the spec's dynamics.
  double operator()(double fn, double zeta) const;
  /// Its rows: they serve fit_extension of the spec where nothing is held.
  const DesignRows& rows() const noexcept { return rows_; }

 private:
  const DiagnosisRecord& r_;
  ExtensionSpec spec_;
  std::vector<double> held_;  ///< held_search_target of the spec
  DesignRows rows_;           ///< of the spec, or of its hysteresis against held_
};

/// Classical PI structure: `plays` thresholds uniform on half the input span.
ModelStructure pi_structure(const DiagnosisRecord& r, int plays);

/// u delayed by d >= 0 samples, a fraction interpolated as the model's DelayLine does (u[0]
/// before the start).
std::vector<double> delayed(std::span<const double> u, double d);

/// The hysteresis of `model` as a structure the designs can refit (its thresholds, dead zones,
/// asymmetry scales, rate range and creep lags); the parameters that are not thresholds are
/// refitted. std::nullopt for a model the designs cannot represent.
std::optional<ModelStructure> structure_of(const ActuatorModel& model, const DiagnosisRecord& r);

}  // namespace hystbench::compensation::details
