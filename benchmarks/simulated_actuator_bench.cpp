// Cost of one tick of the simulated actuator at 10 kHz (the loopback's plant): the default truth,
// the default with every effect on (rate dependence, delay, random-walk drift, displacement
// stops), and the modified-PI truth. Budget: 5 µs per tick with every effect on.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "hystbench/sim/simulated_actuator.hpp"
#include "support/every_effect_on.hpp"
#include "support/random_models.hpp"

namespace hs = hystbench::sim;

namespace {

void actuator_step(benchmark::State& state, const hs::SimulatedActuatorConfig& config) {
  hs::SimulatedActuator a(config, 1e-4);
  // Sweeps of up to 200 samples between random levels: reversals keep the memory busy.
  std::mt19937_64 rng(1);
  const auto u = hystbench::testing::random_reversal_signal(rng, 1 << 16, 0.0, 150.0);
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(a.step(u[k]));
    if (++k == u.size()) k = 0;
  }
  state.SetLabel("ns/tick = time");
}

}  // namespace

BENCHMARK_CAPTURE(actuator_step, default_truth, hs::SimulatedActuatorConfig{});
BENCHMARK_CAPTURE(actuator_step, every_effect_on, hystbench::testing::every_effect_on());
BENCHMARK_CAPTURE(actuator_step, modified_pi_truth,
                  hs::SimulatedActuatorConfig::modified_pi_truth());
