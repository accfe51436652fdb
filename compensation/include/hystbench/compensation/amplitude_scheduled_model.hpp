#pragma once
// A model of several inputs and outputs whose dynamics change with the drive's amplitude (a mode
// that moves as the drive grows): local Hammerstein models, each fitted at one amplitude, their
// outputs blended by a schedule on an estimate of the input's amplitude (a linear
// parameter-varying model in the local form, interpolated between its local models):
//   a(t) = the rms over the inputs of each input's standard deviation over the last window
//          (since the start while it is shorter) [input unit]
//   y(t) = sum_i w_i(a(t)) y_i(t), y_i the local model i's output from rest.
// The weights sum to 1: linear between the two amplitudes either side of a(t); below the first
// or above the last, extrapolated linearly from the two nearest, at most one spacing further,
// then held. One local model: its output alone. Units: the inputs' and outputs' as given.
// Pure maths; simulate() allocates its result.
#include <Eigen/Dense>
#include <cstddef>
#include <span>
#include <vector>

#include "hystbench/compensation/hammerstein_mimo_model.hpp"

namespace hystbench::compensation {

/// The schedule's weights at amplitude a over `amplitudes` (ascending, distinct, >= 1 of them):
/// one per amplitude, summing to 1 (see the header comment).
Eigen::VectorXd schedule_weights(std::span<const double> amplitudes, double a);

/// a(t) per sample of u (m x N): the rms over the m inputs of each one's standard deviation over
/// the last `window` samples (>= 1), over the samples so far while fewer [input unit].
Eigen::VectorXd amplitude_estimate(const Eigen::MatrixXd& u, std::size_t window);

/// A whole record's amplitude: the rms over the inputs of each one's standard deviation over u's
/// columns (the amplitude the estimate settles at on a stationary drive) [input unit].
double record_amplitude(const Eigen::MatrixXd& u);

class AmplitudeScheduledMimoModel {
 public:
  /// amplitudes ascending and distinct (> 0), one per local model; the local models of as many
  /// inputs and outputs and one sample period; window_s > 0 [s]. Throws std::invalid_argument
  /// naming what does not fit.
  AmplitudeScheduledMimoModel(std::vector<double> amplitudes,
                              std::vector<HammersteinMimoModel> local, double window_s);

  std::size_t inputs() const noexcept { return local_.front().inputs(); }
  std::size_t outputs() const noexcept { return local_.front().outputs(); }
  double sample_period_s() const noexcept { return local_.front().sample_period_s(); }
  double window_s() const noexcept { return window_s_; }
  /// The window in samples (>= 1).
  std::size_t window_samples() const noexcept;
  const std::vector<double>& amplitudes() const noexcept { return amplitudes_; }
  const std::vector<HammersteinMimoModel>& local_models() const noexcept { return local_; }

  /// Output (p x N) for input u (m x N), from rest.
  Eigen::MatrixXd simulate(const Eigen::MatrixXd& u) const;
  /// The same model without local model i (< the count, 2 or more): what the others predict at
  /// its amplitude (a leave-one-out check).
  AmplitudeScheduledMimoModel without(std::size_t i) const;

 private:
  std::vector<double> amplitudes_;
  std::vector<HammersteinMimoModel> local_;
  double window_s_;
};

}  // namespace hystbench::compensation
