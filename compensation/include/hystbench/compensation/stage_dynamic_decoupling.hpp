#pragma once
// Dynamic decoupling of a stage of several axes for a reference known ahead of time. The static
// decoupling (stage_decoupling.hpp) takes K_ij s_j off axis i's target. On a stage whose axes
// share a mode, the coupling from axis j's stroke v_j (what its feedforward commands for its own
// target s_j) to axis i's output rises by 1 / (2 zeta) at that mode and lags; and axis i's own
// response, which must carry the correction, lags too where its model holds no dynamics. A fast
// reference's corners leave on the other axes what the static gains do not take out.
//  - coupling_path(): the path P_ij, unit DC gain, from the stage's measured responses: each
//    operating point's cross response G_ij over the receiving axis's own G_ii as its feedforward
//    leaves it (G_ii over its model's inverted mode, where it has one), each at unit
//    low-frequency gain (their mean over the lowest tenth of lines), fitted by least squares
//    over the lines both have with coherence >= 0.5 as
//      P(jw) = e^{-jw tau} (d + sum_m w_m M_m(jw) + a D1(jw) + b D2(jw)),  d + sum_m w_m = 1,
//    M_m the modes that ratio shows (measured_modes: peaks that stand out of their neighbourhood
//    by 3 dB and reach within 10 dB of its low-frequency gain), each discretised for a held
//    input, D1 and D2 the central first and second differences over one sample (the inverse of
//    a receiving axis's own mode is a lead of this kind), and tau the best of a grid of
//    twentieths of a sample from -2 (a lead) to 3. None
//    where the ratio is flat over the measured lines.
//  - DynamicStageDecoupler::own_targets(): the own targets s with
//      s_i = r_i - sum_{j != i} K_ij P_ij[v_j(s_j)],
//    solved by successive substitution from the static solution (each sweep filters every
//    path over the whole reference, a lead reading ahead in it; the map contracts while
//    |K_ij K_ji P_ij P_ji| < 1). Paths without a shape are static, so a stage without measured
//    modes gets the static decoupling's targets.
// Units: the outputs' (µm), seconds. Construction and own_targets() allocate and throw: not
// real-time (the bench runs them while it prepares a run).
#include <Eigen/Dense>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "hystbench/compensation/measured_response.hpp"
#include "hystbench/compensation/second_order_dynamics.hpp"

namespace hystbench::compensation {

/// A coupling path's dynamics with unit DC gain: `direct` passes as it is, each mode's share
/// through it.
struct CouplingPathShape {
  struct Mode {
    DynamicsParameters parameters;
    double share = 0.0;
  };
  double direct = 1.0;
  std::vector<Mode> modes;
  double lag_samples = 0.0;  ///< a pure lag before them [samples]; < 0 a lead
  /// The weights of the (lagged) stroke's central first and second differences [samples,
  /// samples^2]: what a receiving axis's own mode asks of the correction (its inverse's lead).
  double slope = 0.0, curvature = 0.0;
  /// The fit's rms misfit over the lines it used, per unit of the path's DC gain.
  double misfit = 0.0;
};

/// The shape of the path from axis j to axis i: `cross` its responses at several operating
/// points (sampled at dt_s), `own` axis i's own responses at the same operating points (index
/// for index, the same lines; empty: the path's own shape, without the receiving axis's), and
/// `inverted` the mode axis i's model holds (its feedforward inverts it; nullopt: none).
/// nullopt where the ratio shows no mode, or too few lines are usable.
std::optional<CouplingPathShape> coupling_path(std::span<const MeasuredResponse> cross,
                                               std::span<const MeasuredResponse> own,
                                               const std::optional<DynamicsParameters>& inverted,
                                               double dt_s);

class DynamicStageDecoupler {
 public:
  /// paths[i][j]: the shape of the path from axis j to axis i (nullopt: static); empty: every
  /// path is static.
  using PathShapes = std::vector<std::vector<std::optional<CouplingPathShape>>>;
  /// What axis j's feedforward commands for own targets `own` (one per sample), written to
  /// `stroke` (same length): the inversion of its model's dynamics. Empty: the targets
  /// themselves (a model without dynamics).
  using StrokeOf = std::function<void(std::span<const double> own, std::span<double> stroke)>;

  /// gains: K, square, zero diagonal, I + K well conditioned (StageDecoupler's rules); paths
  /// sized axes x axes or empty; dt_s > 0 the loop period. Throws std::invalid_argument naming
  /// the cause.
  DynamicStageDecoupler(const Eigen::MatrixXd& gains, PathShapes paths, double dt_s);

  std::size_t axes() const noexcept { return static_cast<std::size_t>(gains_.rows()); }
  /// True when at least one path has a mode.
  bool dynamic() const noexcept;
  const PathShapes& paths() const noexcept { return paths_; }

  struct Solution {
    Eigen::MatrixXd own;  ///< axes x samples: each axis's own displacement target
    int sweeps = 0;       ///< substitutions until the largest change fell below the tolerance
    double change = 0.0;  ///< the last sweep's largest change [output unit]
  };
  /// The own targets for the stage's reference `stage` (axes x samples, each filter starting
  /// settled at its first value). `strokes` is empty or has one entry per axis. Stops when a
  /// sweep changes no target by more than 1e-9 of the reference's largest magnitude (at most
  /// 50 sweeps). Throws std::invalid_argument for a shape that does not match, a non-finite
  /// value, or substitutions that do not converge (the coupling too strong at its mode to be
  /// inverted this way).
  Solution own_targets(const Eigen::MatrixXd& stage, std::span<const StrokeOf> strokes = {}) const;

 private:
  Eigen::MatrixXd gains_;
  Eigen::MatrixXd static_inverse_;  // (I + K)^{-1}: the first sweep's start
  PathShapes paths_;
  double dt_s_ = 0.0;
};

}  // namespace hystbench::compensation
