#pragma once
// Common interface of the hysteresis models: the Prandtl-Ishlinskii family and the Preisach model.
// Units are the caller's: input typically V, output typically µm.
// step()/peek()/reset() are real-time safe: no allocation, no exceptions, O(number of operators).
#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "hystbench/compensation/invertibility.hpp"
#include "hystbench/compensation/thresholds_rate_law.hpp"

namespace hystbench::compensation {

enum class ModelKind {
  kPi,               ///< classical PI: weighted plays + offset
  kModifiedPi,       ///< Kuhnen's modified PI: PI followed by 2m+1 one-sided dead zones
  kCoupledPlayPi,    ///< asymmetric PI of coupled-play operators (r, ra, rb, rc)
  kRateDependentPi,  ///< modified PI whose cumulative play weights are linear in |du/dt|
  kPreisach,         ///< Preisach relays with a density on a grid (preisach_model.hpp)
};

/// "pi", "mpi", "cpi", "rpi", "preisach".
std::string_view to_string(ModelKind kind) noexcept;
std::optional<ModelKind> model_kind_from_string(std::string_view name) noexcept;

class HysteresisModel {
 public:
  virtual ~HysteresisModel() = default;

  virtual ModelKind kind() const noexcept = 0;
  /// Advances one sample with input u; returns the output.
  virtual double step(double u) noexcept = 0;
  /// Output the model would give for input u now, without changing its state.
  virtual double peek(double u) const noexcept = 0;
  /// As peek(), with any rate-dependent term at the given input rate [input unit / s] instead
  /// of the one u would make (an inverse solves against this with a rate it predicts from the
  /// reference). Rate-independent models ignore the rate.
  virtual double peek_at_rate(double u, double /*rate*/) const noexcept { return peek(u); }
  /// The input rate [input unit / s] at which peek_at_rate(u, rate) = y, for a model whose
  /// output grows with the rate: 0 when even rate 0 gives more than y, +inf when no rate gives
  /// y (the caller caps it). Rate-independent models return NaN.
  virtual double rate_for_output(double /*u*/, double /*y*/) const noexcept;
  /// Relaxed state at input u0: every play output equals u0 (and the previous input is u0).
  virtual void reset(double u0) noexcept = 0;
  /// Sample period in seconds; only rate-dependent models use it. Not real-time safe.
  virtual void set_sample_period(double /*dt_s*/) {}
  /// The thresholds rate law the model carries (thresholds_rate_law.hpp): the rate-dependent
  /// PI's thresholds law, the Preisach plane's; nullopt for none.
  virtual std::optional<ThresholdsRateLaw> thresholds_law() const { return std::nullopt; }
  /// The same model without its rate law (its output at rate 0, its state at reset); nullptr for
  /// a model without one. Not real-time safe.
  virtual std::unique_ptr<HysteresisModel> rate_free_part() const { return nullptr; }
  /// Number of elementary operators (plays + dead zones + ...), for reports and benchmarks.
  virtual std::size_t operator_count() const noexcept = 0;
  /// Checked, never assumed: names the first offending block and index.
  virtual Invertibility invertibility() const = 0;
  virtual std::unique_ptr<HysteresisModel> clone() const = 0;

  /// Steps over a whole signal from the current state.
  std::vector<double> simulate(std::span<const double> u);
};

}  // namespace hystbench::compensation
