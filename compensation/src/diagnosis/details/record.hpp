#pragma once
// The record as the diagnosis sees it (diagnosis internals): samples, the interleaved
// fit / held-out split, the row thinning of searches, and error statistics per part.
#include <cstddef>
#include <span>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/diagnosis.hpp"
#include "hystbench/compensation/error_metrics.hpp"

namespace hystbench::compensation::details {

/// Which part of the record a sample belongs to.
enum Part : unsigned char {
  kFitPart = 0,
  kHeldoutPart = 1,
  kSkippedPart = 2,  ///< start-up: simulated, neither fitted nor scored
};

/// Takes every stride-th of the rows it is asked about: the first, then each stride-th after it
/// (a search's rows among the fit rows), without a division per sample.
class EveryNth {
 public:
  explicit EveryNth(std::size_t stride) noexcept : stride_(stride > 0 ? stride : 1) {}
  bool take() noexcept {
    if (left_ > 0) {
      --left_;
      return false;
    }
    left_ = stride_ - 1;
    return true;
  }

 private:
  std::size_t stride_;
  std::size_t left_ = 0;
};

struct DiagnosisRecord {
  std::span<const double> t, u, y;
  std::size_t n = 0;
  double dt = 0.0;  ///< mean sample period [s]
  DataSplit split;
  std::vector<unsigned char> part;  ///< Part of every sample
  bool fit_row(std::size_t k) const noexcept { return part[k] == kFitPart; }
  /// Searches fit every search_stride-th fit row only (final fits use every row).
  std::size_t search_stride = 1;
  double u_lo = 0.0, u_hi = 0.0;  ///< input range over the whole record
  double y_lo = 0.0, y_hi = 0.0;  ///< output range over the fit part
  Units units;

  double duration() const noexcept { return dt * static_cast<double>(n - 1); }
  /// Split blocks per held-out period; the drift knots are that far apart, so that every
  /// held-out block lies between two knots fitted on its neighbours, and the drift stays slower
  /// than the input's own slow structure (holds, loop segments), which it must not absorb.
  std::size_t heldout_every = 4;

  std::size_t block_samples() const noexcept { return n / split.blocks; }
  std::size_t drift_knot_samples() const noexcept { return block_samples() * heldout_every; }
  /// Drift knots after t = 0 (the knot at 0 is the model's offset).
  std::size_t drift_knots() const noexcept { return split.blocks / heldout_every; }
  /// The first sample a drift is fitted on: the end of the record's unscored start, 0 without.
  std::size_t drift_origin() const noexcept {
    return !split.skipped_ranges.empty() && split.skipped_ranges.front().first == 0
               ? split.skipped_ranges.front().second
               : 0;
  }
};

/// `blocks` equal blocks, block b held out when b % heldout_every == heldout_every / 2; a
/// held-out block without input steps moves by one block onto a neighbour with steps until
/// the held-out part has its share of the steps (1 / heldout_every, at least one when the input
/// has two or more, at most half). Uses the input only.
DataSplit make_split(std::span<const double> u, int blocks, int heldout_every);

/// Validated record (lengths, finiteness, increasing t, non-constant u and y, enough samples).
/// `record_starts`: the record is several records end to end, each starting at one of these
/// samples (0 implied); each one's start is left out until its own input has reached both its
/// extremes. Throws std::invalid_argument with a clear message.
DiagnosisRecord make_diagnosis_record(std::span<const double> t, std::span<const double> u,
                                      std::span<const double> y, const DiagnosisOptions& o,
                                      std::span<const std::size_t> record_starts = {});

/// Error statistics of a whole-record prediction on the fit part and on the held-out part
/// (the start-up samples in neither).
struct SplitErrors {
  ErrorStats fit, heldout;
};
SplitErrors split_errors(const DiagnosisRecord& r, std::span<const double> prediction);

}  // namespace hystbench::compensation::details
