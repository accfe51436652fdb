#include "hystbench/sim/modal_dynamics.hpp"

namespace hystbench::sim {

ModalDynamics::ModalDynamics(std::span<const Mode> modes, double dt_s) {
  modes_.reserve(modes.size());
  for (const Mode& m : modes) {
    modes_.emplace_back(compensation::DynamicsParameters{m.frequency_hz, m.damping_ratio}, dt_s);
    gains_.push_back(m.gain);
  }
}

}  // namespace hystbench::sim
