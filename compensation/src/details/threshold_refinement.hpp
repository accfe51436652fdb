#pragma once
// Levenberg-Marquardt refinement of a structure's thresholds by variable projection: for given
// thresholds the weights are the constrained least-squares solution (fit_design), and LM
// minimises the simulated output error over the thresholds alone. Thresholds are packed as
// logarithms of their increments, so they stay ordered and positive for any step.
#include <limits>
#include <span>

#include "details/designs.hpp"

namespace hystbench::compensation::details {

struct RefinementRecord {
  std::span<const double> u;  ///< input as the hysteresis sees it (after any delay)
  std::span<const double> y;
  std::size_t begin = 0;  ///< residuals on [begin, end); the model runs from sample 0
  std::size_t end = 0;
  std::size_t stride = 1;  ///< every stride-th row of [begin, end) is fitted and compared

  std::size_t residuals() const noexcept {
    return end > begin ? (end - begin - 1) / stride + 1 : 0;
  }
};

struct RefinementSettings {
  bool plays = true;       ///< refine play thresholds r_1 .. r_{n-1}
  bool dead_zones = true;  ///< refine inverse dead-zone thresholds (MPI / RPI)
  bool asymmetry = true;   ///< refine the coupled-play scales (CPI), keeping them monotone
  int max_iterations = 15;
  /// Rows the search works on at most (a stride thins longer records; the result is then
  /// re-scored on every row by the caller).
  std::size_t max_rows = 8000;
};

struct RefinementResult {
  ModelStructure structure;
  double initial_rmse = 0.0;
  double final_rmse = 0.0;
  int evaluations = 0;
};

/// The threshold after `previous` at the gap exp(log_gap), at least min_gap above it: strictly
/// increasing for any log_gap (a gap that exp() shrinks below previous's last digit would
/// otherwise round to nothing, and equal thresholds are no model). min_gap > 0. At most max_gap
/// above it (>= min_gap): a threshold the search drives beyond the data never moves, and its
/// play is a constant that depends on where the record began.
double next_threshold(double previous, double log_gap, double min_gap,
                      double max_gap = std::numeric_limits<double>::infinity()) noexcept;
/// The smallest gap kept between refined thresholds that span `span` (a millionth of it, of 1
/// when it is smaller).
double min_threshold_gap(double span) noexcept;

/// Simulated output RMS error of the structure fitted on `record`.
double structure_rmse(const ModelStructure& s, const RefinementRecord& record);

/// Refines the thresholds; returns the input structure when nothing can be refined.
RefinementResult refine_structure(const ModelStructure& s, const RefinementRecord& record,
                                  const RefinementSettings& settings);

}  // namespace hystbench::compensation::details
