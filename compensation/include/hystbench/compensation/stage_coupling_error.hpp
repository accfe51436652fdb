#pragma once
// What the other axes' motion left on each axis of a stage during a run: each axis's tracking
// error regressed (least squares, with an intercept) on the other axes' measured outputs. The
// fitted gains are the coupling the run did not take out (with static decoupling, what its
// estimate missed; without, the coupling itself), and the rms of the fitted part is the error
// they explain. Units: µm. Allocates and throws: not for the real-time path.
#include <Eigen/Dense>

namespace hystbench::compensation {

struct CouplingErrorLeft {
  /// axes x axes, zero diagonal: gains(i, j), axis i's error per µm of axis j's motion.
  Eigen::MatrixXd gains;
  /// Per axis, the rms of its error the other axes' motion explains [µm].
  Eigen::VectorXd rms_um;
  /// Per axis, the rms of its whole error [µm] (the same samples).
  Eigen::VectorXd error_rms_um;
};

/// errors and outputs: axes x samples, a run's tracking errors (measured - reference) and
/// measured outputs over its scored part. Throws std::invalid_argument naming the cause:
/// different shapes, fewer than two axes or than 10 samples per axis, a non-finite value.
/// An axis that did not move (its output's standard deviation 0) explains nothing (gain 0).
CouplingErrorLeft coupling_error_left(const Eigen::MatrixXd& errors,
                                      const Eigen::MatrixXd& outputs);

}  // namespace hystbench::compensation
