#pragma once
// Shared helpers of the loop tests: a linear stage (a gain, one mode, whole samples of delay) in
// time, and its frequency responses measured as the bench measures them.
#include <cstddef>
#include <span>
#include <vector>

#include "hystbench/compensation/measured_response.hpp"
#include "hystbench/compensation/second_order_dynamics.hpp"
#include "hystbench/sim/frequency_response_excitation.hpp"

namespace hystbench::test {

namespace hc = hystbench::compensation;
namespace hs = hystbench::sim;

// A stage: gain g, a mode (exact for a held input), d whole samples of delay. The reading at a
// tick answers that tick's drive (as the loopback's does).
struct Stage {
  double gain = 1.0;
  hc::DynamicsParameters mode{3000.0, 0.06};
  int delay = 0;
  double dt = 1e-4;
};

class StageSimulation {
 public:
  explicit StageSimulation(const Stage& s) : s_(s), mode_(s.mode, s.dt), line_(s.delay + 1, 0.0) {}
  double step(double u) {
    line_[k_ % line_.size()] = u;
    const double ud = line_[(k_ + 1) % line_.size()];
    ++k_;
    return s_.gain * mode_.step(ud);
  }

 private:
  Stage s_;
  hc::SecondOrderDynamics mode_;
  std::vector<double> line_;
  std::size_t k_ = 0;
};

// The stage's responses, measured as the bench measures them (the default excitation's
// conditions), noise-free.
inline std::vector<hc::MeasuredResponse> measured(const Stage& s) {
  hs::FrequencyResponseExcitationOptions o;
  o.rate_hz = 1.0 / s.dt;
  const hs::FrequencyResponseExcitation x = hs::make_frequency_response_excitation(o);
  StageSimulation sim(s);
  std::vector<double> y;
  for (const double u : x.u) y.push_back(sim.step(u));
  std::vector<hc::MeasuredResponse> out;
  for (const auto& seg : x.segments) {
    const std::size_t n = x.period * seg.periods;
    hc::MeasuredResponse r =
        hc::estimate_response(std::span(x.u).subspan(seg.first, n),
                              std::span(y).subspan(seg.first, n), x.period, x.lines, o.rate_hz);
    r.output_noise_rms = 1e-3;  // a sensor's, for the noise budget
    r.label = seg.label;
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace hystbench::test
