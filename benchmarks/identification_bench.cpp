// Identification time: modified PI, 100 000 samples, 20 plays + 2m+1 = 11 dead zones, fixed
// order (target <= 200 ms without threshold refinement), and the pieces it is made of.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"

namespace hc = hystbench::compensation;

namespace {

struct Record {
  std::vector<double> t, u, y;
};

// 1 kHz record: decaying 1 Hz sine with a faster component (nested minor loops) driving an
// asymmetric modified PI, plus 0.5 % noise.
const Record& record(std::size_t n) {
  static Record r;
  if (r.u.size() == n) return r;
  r.t.resize(n), r.u.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = 1e-3 * static_cast<double>(k);
    const double envelope = 1.0 - 0.8 * static_cast<double>(k) / static_cast<double>(n);
    const double phase = 2.0 * std::numbers::pi * t;
    r.t[k] = t;
    r.u[k] = 50.0 + 50.0 * envelope * (0.75 * std::sin(phase) + 0.25 * std::sin(4.3 * phase));
  }
  hc::ModifiedPiParameters p;
  p.play.thresholds = hc::uniform_thresholds(12, 50.0);
  p.play.weights = {0.5, 0.1, 0.08, 0.05, 0.04, -0.02, 0.03, 0.02, 0.01, 0.01, -0.01, 0.01};
  p.center = 40.0;
  p.dead_zone = {{-20.0, -8.0, 0.0, 10.0, 25.0}, {0.2, -0.1, 1.0, -0.3, 0.4}};
  hc::ModifiedPiModel model(p);
  model.reset(r.u[0]);
  r.y = model.simulate(r.u);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.4);
  for (double& v : r.y) v += noise(rng);
  return r;
}

hc::FitOptions fixed_order(bool refine) {
  hc::FitOptions o;
  o.kind = hc::ModelKind::kModifiedPi;
  o.operators = 20;
  o.dead_zones = 5;
  o.delay_samples = 0;
  o.refine_thresholds = refine;
  return o;
}

void BM_IdentifyMpiFixedOrder(benchmark::State& state) {
  const Record& r = record(static_cast<std::size_t>(state.range(0)));
  const hc::FitOptions o = fixed_order(false);
  double rmse = 0.0;  // reported as a label: libbenchmark 1.7's double counters are garbled
  for (auto _ : state) {
    // fit_model cannot be optimised away (it allocates and returns a model); no
    // DoNotOptimize on a double: with GCC -O3 libbenchmark 1.7's "+m,r" asm garbles it.
    rmse = hc::fit_model(r.t, r.u, r.y, o).heldout.rmse;
  }
  state.SetLabel("held-out RMS " + std::to_string(rmse));
}
BENCHMARK(BM_IdentifyMpiFixedOrder)->Arg(100000)->Unit(benchmark::kMillisecond);

void BM_IdentifyMpiFixedOrderRefined(benchmark::State& state) {
  const Record& r = record(static_cast<std::size_t>(state.range(0)));
  const hc::FitOptions o = fixed_order(true);
  double rmse = 0.0;
  for (auto _ : state) {
    rmse = hc::fit_model(r.t, r.u, r.y, o).heldout.rmse;
  }
  state.SetLabel("held-out RMS " + std::to_string(rmse));
}
BENCHMARK(BM_IdentifyMpiFixedOrderRefined)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

void BM_IdentifyMpiAutomaticOrder(benchmark::State& state) {
  const Record& r = record(static_cast<std::size_t>(state.range(0)));
  hc::FitOptions o;
  o.refine_thresholds = false;
  o.delay_samples = 0;
  std::string chosen;
  for (auto _ : state) {
    const hc::FitResult fit = hc::fit_model(r.t, r.u, r.y, o);
    chosen = std::to_string(fit.operators) + " plays, m = " + std::to_string(fit.dead_zones) +
             ", held-out RMS " + std::to_string(fit.heldout.rmse);
  }
  state.SetLabel(chosen);
}
BENCHMARK(BM_IdentifyMpiAutomaticOrder)->Arg(100000)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
