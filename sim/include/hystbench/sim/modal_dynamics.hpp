#pragma once
// Structural dynamics as a sum of second-order modes with unit DC gain in all:
//   G(s) = sum_i g_i wn_i^2 / (s^2 + 2 zeta_i wn_i s + wn_i^2),   sum_i g_i = 1,
// each discretised exactly for a zero-order-held input (compensation::SecondOrderDynamics).
// Construction allocates and throws; step()/reset() are real-time safe.
#include <span>
#include <vector>

#include "hystbench/compensation/second_order_dynamics.hpp"

namespace hystbench::sim {

struct Mode {
  double frequency_hz = 3000.0;  ///< > 0 [Hz]
  double damping_ratio = 0.05;   ///< > 0
  double gain = 1.0;             ///< share of the DC gain
};

class ModalDynamics {
 public:
  ModalDynamics() = default;
  /// Throws std::invalid_argument for a bad mode or sample period.
  ModalDynamics(std::span<const Mode> modes, double dt_s);

  /// Holds x for one sample period; returns the output at its end.
  double step(double x) noexcept {
    double y = 0.0;
    for (std::size_t i = 0; i < modes_.size(); ++i) y += gains_[i] * modes_[i].step(x);
    return modes_.empty() ? x : y;
  }
  /// Settled at input x0 (the output is then x0 times the gains' sum).
  void reset(double x0) noexcept {
    for (auto& m : modes_) m.reset(x0);
  }
  bool empty() const noexcept { return modes_.empty(); }

 private:
  std::vector<compensation::SecondOrderDynamics> modes_;
  std::vector<double> gains_;
};

}  // namespace hystbench::sim
