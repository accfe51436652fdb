#pragma once
// The Preisach model, nonparametric: relays (up at alpha, down at beta <= alpha) with a density
// over the Preisach plane u_min <= beta <= alpha <= u_max, piecewise constant on an N x N grid of
// cells (the diagonal ones half squares), plus a reversible slope and an offset, then an output
// map (Kuhnen's superposition of one-sided dead zones, dead_zone.hpp; the identity by default):
//   x(t) = offset + slope u(t) + integral over the relays that are up of density
//   y(t) = center + S[x(t)]
// The relays that are up are bounded by a staircase of the input's dominant extrema (the
// memory: each new maximum above an old one wipes it and the minimum after it out; likewise
// downward). With the Everett function G(a, b), the density's integral over the triangle
// b <= beta <= alpha <= a (exact for the piecewise-constant density, O(1) from prefix tables):
//   y = offset + slope u + sum over the memory's maxima M_k, between minima m_(k-1) and m_k,
//       of G(M_k, m_(k-1)) - G(M_k, m_k)     (the input now closing the last term)
// so x is continuous and linear in the densities (the identification's columns are each cell's
// area in the up region, cell_areas()). With densities >= 0, slope >= 0 and an invertible map
// (its weights' running sums > 0 outward) the output never falls as the input rises: the model
// is invertible. Inputs outside [u_min, u_max]
// move only the slope's term (every relay already switched). The memory holds kMaxExtrema
// extrema; a reversal beyond that is not remembered (a minor loop below the grid's scale).
// The thresholds rate law (thresholds_rate_law.hpp), when active: every relay's thresholds
// widen by w(|du/dt|) (up at alpha + w, down at beta - w), so the relays see the input through a
// play of half-width w, the front f(t) = clamp(f(t-1), u - w, u + w), which lags a rising input
// and leads a falling one and meets it where the input reverses; the reversible slope does not
// lag (x = offset + slope u + relays of f). Needs set_sample_period().
// Not the PI family: no play operators; Mayergoyz's representation, its density discretised
// without a parametric form. step()/peek()/peek_at_rate()/reset() are real-time safe (no
// allocation).
#include <array>
#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "hystbench/compensation/dead_zone.hpp"
#include "hystbench/compensation/hysteresis_model.hpp"
#include "hystbench/compensation/rate_estimator.hpp"
#include "hystbench/compensation/thresholds_rate_law.hpp"

namespace hystbench::compensation {

struct PreisachParameters {
  double u_min = 0.0, u_max = 1.0;  ///< the plane's input range [input unit], u_min < u_max
  std::size_t cells = 1;            ///< N, cells per side, in [1, PreisachModel::kMaxCells]
  /// N (N + 1) / 2 densities >= 0 [output unit / input unit^2], cell (p, q) (alpha in row p,
  /// beta in column q <= p) at PreisachModel::cell_index(p, q) = p (p + 1) / 2 + q.
  std::vector<double> densities;
  double slope = 0.0;   ///< the reversible part [output unit / input unit], >= 0
  double offset = 0.0;  ///< [output unit]
  /// S, the output map of x - (its identity: one operator at 0 of weight 1).
  DeadZoneParameters output_map{{0.0}, {1.0}};
  double center = 0.0;  ///< [output unit]
  /// The relays' thresholds widening with the input's rate; inactive (threshold_rate_s 0) by
  /// default. Model files without it: inactive.
  ThresholdsRateLaw rate_law{};
};

class PreisachModel final : public HysteresisModel {
 public:
  static constexpr std::size_t kMaxCells = 64;
  static constexpr std::size_t kMaxExtrema = 128;

  /// Throws std::invalid_argument naming the field.
  explicit PreisachModel(PreisachParameters p);

  ModelKind kind() const noexcept override { return ModelKind::kPreisach; }
  double step(double u) noexcept override;
  double peek(double u) const noexcept override;
  /// As peek(), the relays' widening at the given rate [input unit / s].
  double peek_at_rate(double u, double rate) const noexcept override;
  /// Relaxed at u0: from every relay down (u_min), the input risen to u0; the front at u0.
  void reset(double u0) noexcept override;
  void set_sample_period(double dt_s) override;
  std::optional<ThresholdsRateLaw> thresholds_law() const override;
  /// The same plane without its rate law.
  std::unique_ptr<HysteresisModel> rate_free_part() const override;
  std::size_t operator_count() const noexcept override { return p_.densities.size(); }
  Invertibility invertibility() const override;
  std::unique_ptr<HysteresisModel> clone() const override;

  const PreisachParameters& parameters() const noexcept { return p_; }
  /// The density's integral over b <= beta <= alpha <= a (0 for a <= b), both clamped to the
  /// plane [output unit].
  double everett(double a, double b) const noexcept;
  /// Each cell's area in the up region now, the input at u (as step(u) would leave it, without
  /// stepping) [input unit^2]: x is offset + slope u + sum densities x areas.
  void cell_areas(double u, std::span<double> out) const noexcept;
  /// step(u) without computing the output, then the cell areas of the state it leaves (what
  /// cell_areas(u) then step(u) give, at about half the work): the identification's rows.
  /// Real-time safe.
  void step_cell_areas(double u, std::span<double> out) noexcept;
  /// step_cell_areas(u) without the areas: the relays' state stepped alone (a row the fit skips).
  /// Real-time safe.
  void step_relays(double u) noexcept;
  /// The input the relays see for input u at rate [input unit / s]: u without a rate law.
  double front(double u, double rate) const noexcept;
  /// Cells in the triangle of N cells per side.
  static std::size_t cell_count(std::size_t n) noexcept { return n * (n + 1) / 2; }
  /// The index of cell (p, q), alpha in row p, beta in column q <= p, in densities.
  static std::size_t cell_index(std::size_t p, std::size_t q) noexcept { return cell_count(p) + q; }

 private:
  // The memory: its extrema, how many, and p[i], the sum of the terms its first i extrema close
  // (so that an output reads one Everett value, not one per extremum).
  struct Memory {
    std::array<double, kMaxExtrema> e{};
    std::array<double, kMaxExtrema + 1> p{};
    std::size_t n = 0;
  };
  /// Each cell's area in the up region of memory m, the input at x, written to out.
  void write_cell_areas(const Memory& m, double x, std::span<double> out) const noexcept;
  /// Adds each cell's area in {from <= beta < to, beta <= alpha <= top} to out.
  void add_stripe_areas(double from, double to, double top, std::span<double> out) const noexcept;
  // What an input x does to a memory, without changing it: its new size, and where the last
  // input joins it (kNoPush: it does not) with the prefix sum there.
  static constexpr std::size_t kNoPush = kMaxExtrema + 1;
  struct Turn {
    std::size_t n;
    std::size_t pushed_at;
    double pushed_prefix;
  };
  Turn turn(const Memory& m, double x) const noexcept;
  // The term an extremum v closes, pushed at index n of m.
  double closing(const Memory& m, std::size_t n, double v) const noexcept;
  void apply(double u, Memory& m) const noexcept;
  double hysteresis(const Memory& m, const Turn& t, double x) const noexcept;
  double clamp(double u) const noexcept;
  // The relays' output for the front x (clamped), without changing the memory.
  double relays(double x) const noexcept;

  PreisachParameters p_;
  DeadZoneSuperposition map_;
  double h_ = 1.0;
  std::vector<double> mass_;      // each cell's mass (half for a diagonal cell) [output unit]
  std::vector<double> triangle_;  // G at grid nodes, (N + 1)^2, [i * (N + 1) + j], j <= i
  std::vector<double> row_;       // per row p, prefix over q < p of the off-diagonal masses
  std::vector<double> column_;    // per column q, prefix over p > q of the off-diagonal masses
  Memory memory_;
  double u_ = 0.0;      // the relays' last input (the front), clamped to the plane
  double front_ = 0.0;  // the front, unclamped (rate law)
  RateEstimator rate_;  // |du/dt| as the rate law reads it
  // step()'s last input and output without a rate law: a held input (a record's holds) moves no
  // relay, and its output is returned as it was. NaN after anything else moved the relays.
  double held_u_ = std::numeric_limits<double>::quiet_NaN();
  double held_output_ = 0.0;
};

}  // namespace hystbench::compensation
