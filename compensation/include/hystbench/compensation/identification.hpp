#pragma once
// Identification of PI-family models from a measured record (t, u, y).
// Not real-time: allocates, may take up to a few hundred ms for 1e5 samples.
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/compensation/pi_model.hpp"

namespace hystbench::compensation {

struct FitOptions {
  /// Model family; std::nullopt = "auto": the family with the lowest held-out error.
  std::optional<ModelKind> kind = ModelKind::kModifiedPi;
  /// Number of plays; 0 = chosen by held-out error.
  int operators = 0;
  /// Dead zones per side m (2m+1 dead-zone operators in all); -1 = chosen by held-out error.
  int dead_zones = -1;
  /// Fraction of the record (at its end) kept out of the fit to measure held-out error.
  double heldout_fraction = 0.25;
  /// Levenberg-Marquardt refinement of thresholds, kept only when held-out error improves.
  bool refine_thresholds = true;
  /// Smallest allowed cumulative weight, relative to the data's overall slope range/range.
  double min_cumulative_weight = 1e-3;
  /// Optional progress callback: (fraction done 0..1, what is happening).
  std::function<void(double, const std::string&)> progress;
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
};

/// Fits a model to a record. t [s] strictly increasing, u input, y output, equal lengths.
/// Throws std::invalid_argument with a clear message for too few samples, constant input,
/// NaN, or mismatched lengths.
FitResult fit_model(std::span<const double> t, std::span<const double> u,
                    std::span<const double> y, const FitOptions& options = {});

/// The classical-PI paper's triangular-matrix method (eq. 1-3) on one ascending branch
/// (u increasing from a major-loop minimum to the maximum): thresholds r_i = i*span/(2n)
/// and weights from the lower-triangular system. Offset so the branch start matches.
PiParameters identify_pi_triangular(std::span<const double> u_branch,
                                    std::span<const double> y_branch, int operators);

}  // namespace hystbench::compensation
