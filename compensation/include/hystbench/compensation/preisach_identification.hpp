#pragma once
// The Preisach model (preisach_model.hpp) fitted to a record. Its Preisach part is linear in the
// cell densities, the reversible slope and the offset (each cell's area in the up region is its
// column); its output map S is fitted as Kuhnen fits the modified PI's, by its inverse S' on the
// measured output: S'[y - center] = x, S' = m one-sided dead zones per side (uniform thresholds
// over the record's output range), its slope outward >= kMinMapSlope (S' and S invertible). So
// the fit is one bounded least squares: the densities and the slope >= 0 (an invertible model by
// construction), plus a smoothness penalty lambda x the sum of squared differences between
// neighbouring cells' densities. lambda is chosen on held-out data: each candidate is
// fitted on the record's first part, the model simulated over the whole record, and scored on
// the rest; the best (with the output map that gains most there) is then fitted on the whole
// record. fit_model(kind = preisach) fits the same with creep lags and a drift beside the cells.
// Pure maths, not real-time.
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "hystbench/compensation/preisach_model.hpp"

namespace hystbench::compensation {

struct PreisachFitOptions {
  std::size_t cells = 24;  ///< N, cells per side of the plane, in [1, PreisachModel::kMaxCells]
  /// The plane's input range; u_min >= u_max: the record's own range.
  double u_min = 0.0, u_max = 0.0;
  /// Smoothness weights tried, relative to the columns' mean square (0 = none).
  std::vector<double> smoothness = {0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2};
  double heldout_fraction = 0.25;  ///< the record's last part that scores them, in (0, 0.5]
  /// The output map's dead zones per side tried, each with every smoothness weight (0: the
  /// identity); the best on the held-out part is kept.
  std::vector<std::size_t> output_zones = {0, 3};
  /// Samples before this are simulated, not fitted or scored. Unset: the record's start-up, until
  /// the input has come near both of its extremes (its memory of what came before is then wiped
  /// out: the plane starts from its relaxed state, which a record need not; FitOptions's
  /// automatic skip_samples alike), at most a quarter of the part before the held-out part.
  std::optional<std::size_t> begin;
};

/// The output map's least slope, as its inverse's: 1 / 20 of the identity's.
inline constexpr double kMinMapSlope = 0.05;

struct PreisachFit {
  PreisachParameters parameters;
  double smoothness = 0.0;       ///< the weight kept
  std::size_t output_zones = 0;  ///< the output map's dead zones per side kept
  double heldout_rms = 0.0;      ///< of the fit on the first part, on the rest [output unit]
  double fit_rms = 0.0;          ///< of the kept fit on the whole scored record
  std::size_t begin = 0;         ///< the first sample fitted and scored
  std::vector<double>
      tried_rms;  ///< held-out rms of each smoothness weight, in order (the kept map's)
};

/// Throws std::invalid_argument for mismatched or too short records, non-finite samples or bad
/// options.
PreisachFit fit_preisach(std::span<const double> u, std::span<const double> y,
                         const PreisachFitOptions& o = {});

}  // namespace hystbench::compensation
