// Cost of one tick of the simulated actuator at 10 kHz (the loopback's plant): the default truth,
// the default with every effect on (rate dependence, delay, random-walk drift, displacement
// stops), and the modified-PI truth. Budget: 5 µs per tick with every effect on. And a tick of a
// simulated stage of 2 and 6 coupled axes (every axis the default truth).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "hystbench/sim/simulated_actuator.hpp"
#include "hystbench/sim/simulated_stage.hpp"
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

void stage_step(benchmark::State& state) {
  hs::SimulatedStageConfig c = hs::SimulatedStageConfig::xy();
  const auto n = static_cast<std::size_t>(state.range(0));
  c.axes.resize(n, c.axes[0]);
  c.coupling.gains.assign(n, std::vector<double>(n, 0.03));
  for (std::size_t i = 0; i < n; ++i) {
    c.axes[i].name = "a" + std::to_string(i);
    c.coupling.gains[i][i] = 0.0;
  }
  hs::SimulatedStage stage(c, 1e-4);
  std::mt19937_64 rng(1);
  const auto u = hystbench::testing::random_reversal_signal(rng, 1 << 16, 0.0, 150.0);
  std::vector<double> in(n), out(n);
  std::size_t k = 0;
  for (auto _ : state) {
    // Each axis a shifted copy of the signal: their reversals fall apart.
    for (std::size_t i = 0; i < n; ++i) in[i] = u[(k + 977 * i) % u.size()];
    stage.step(in, out);
    benchmark::DoNotOptimize(out.data());
    if (++k == u.size()) k = 0;
  }
  state.SetLabel("ns/tick = time");
}

}  // namespace

BENCHMARK(stage_step)->Arg(2)->Arg(6);
BENCHMARK_CAPTURE(actuator_step, default_truth, hs::SimulatedActuatorConfig{});
BENCHMARK_CAPTURE(actuator_step, every_effect_on, hystbench::testing::every_effect_on());
BENCHMARK_CAPTURE(actuator_step, modified_pi_truth,
                  hs::SimulatedActuatorConfig::modified_pi_truth());
