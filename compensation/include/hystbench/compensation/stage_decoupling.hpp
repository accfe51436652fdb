#pragma once
// Static decoupling of a stage of several axes (XY scanner, tip-tilt mirror). The coupling as
// the bench sees it: axis i's displacement is its own displacement s_i plus
// sum_{j != i} K_ij s_j, where s_j is axis j's own displacement (from 0 µm) and K_ij the share
// of it that reaches axis i at low frequency. In vector form r = (I + K) s.
//  - estimate_coupling_gains(): K from records in which one axis moved and the others were held:
//    each held axis's output regressed on the moved axis's output (least squares with an
//    intercept, which takes up what the held axes' own displacement adds).
//  - StageDecoupler: the own displacements s = (I + K)^{-1} r that put the stage at r; each
//    axis's inverse then turns s_i into its drive.
//  - fit_stage(): the coupling, then each axis's model fitted (fit_model) on its own
//    displacement: its record's outputs decoupled, so no axis's model holds another's motion.
// Units: the outputs' (µm). Estimation and construction allocate and throw; the decoupler's
// apply()/couple() are real-time safe (no allocation, no exceptions; O(axes^2)).
#include <Eigen/Dense>
#include <cstddef>
#include <span>
#include <vector>

#include "hystbench/compensation/identification.hpp"

namespace hystbench::compensation {

/// One record of a stage's outputs in which only axis `moved` was driven.
struct OneAxisMotion {
  std::size_t moved = 0;    ///< the driven axis, < outputs.rows()
  Eigen::MatrixXd outputs;  ///< axes x samples, every axis's measured displacement
  /// The moved axis's drive, one per sample [V], and the sample period [s] (fit_stage() only).
  std::vector<double> drive;
  double dt = 0.0;
};

struct CouplingEstimate {
  /// axes x axes, zero diagonal: gains(i, j) = K_ij, the share of axis j's motion on axis i.
  Eigen::MatrixXd gains;
  /// axes x axes: the rms of what the regression left on axis i in axis j's record, per µm of
  /// axis j's motion's rms (0 on the diagonal): how well a static gain explains the coupling.
  Eigen::MatrixXd residual_share;
};

/// Throws std::invalid_argument naming the cause: no record, records of different axes counts,
/// a moved index out of range, an axis that no record moved, or one that barely moved (its
/// output's standard deviation under 1e-9 of the largest). Where several records moved one
/// axis, they are pooled.
CouplingEstimate estimate_coupling_gains(std::span<const OneAxisMotion> records);

class StageDecoupler {
 public:
  StageDecoupler() = default;
  /// gains: square, zero diagonal (K). Throws std::invalid_argument for a bad shape, a
  /// non-finite or non-zero diagonal entry, or an I + K that is singular or ill-conditioned
  /// (condition number over 1e3).
  explicit StageDecoupler(const Eigen::MatrixXd& gains);

  std::size_t axes() const noexcept { return static_cast<std::size_t>(inverse_.rows()); }
  const Eigen::MatrixXd& gains() const noexcept { return gains_; }
  /// own = (I + K)^{-1} stage: the own displacements that put the stage at `stage`. Spans of
  /// axes() values; shorter ones are read and written only where they have values.
  void apply(std::span<const double> stage, std::span<double> own) const noexcept;
  /// stage = (I + K) own: where the stage is for own displacements `own` (the coupling's
  /// model).
  void couple(std::span<const double> own, std::span<double> stage) const noexcept;

 private:
  Eigen::MatrixXd gains_;
  Eigen::MatrixXd coupled_;  // I + K
  Eigen::MatrixXd inverse_;  // (I + K)^{-1}
};

struct StageFitOptions {
  FitOptions axis;         ///< each axis's fit (family, orders, held-out part)
  std::size_t stride = 1;  ///< fit every stride-th sample (a 10 kHz record at 1 kHz: 10), >= 1
};

/// A coupling gain in dB: 20 log10 |gain|, -inf for a gain of 0.
double gain_db(double gain) noexcept;

struct StageFit {
  CouplingEstimate coupling;
  std::vector<FitResult> axes;  ///< per axis, its model of its own displacement
  /// 20 log10 |K_ij| [dB], -inf where a gain is 0 (and on the diagonal).
  Eigen::MatrixXd coupling_db;
};

/// One record per axis at least, each moving one axis with its drive given. Throws
/// std::invalid_argument naming the cause: those of estimate_coupling_gains(), a drive whose
/// length differs from its outputs', dt <= 0, stride 0; and fit_model()'s, prefixed with the
/// axis. Where several records moved one axis, its model is fitted on the first.
StageFit fit_stage(std::span<const OneAxisMotion> records, const StageFitOptions& options = {});

}  // namespace hystbench::compensation
