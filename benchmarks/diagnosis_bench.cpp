// Diagnosis time on a 10 kHz record whose actuator has a 3 kHz mode and a 2-sample delay that
// the baseline (its modified PI alone) lacks: the resonance search's joint fits dominate.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "hystbench/compensation/diagnosis.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"

namespace hc = hystbench::compensation;

namespace {

constexpr double kDt = 1e-4;

hc::ActuatorModel baseline() {
  hc::ModifiedPiParameters p;
  p.play.thresholds = hc::uniform_thresholds(12, 50.0);
  p.play.weights = {0.5, 0.1, 0.08, 0.05, 0.04, 0.02, 0.03, 0.02, 0.01, 0.01, 0.01, 0.01};
  p.center = 40.0;
  p.dead_zone = {{-20.0, 0.0, 25.0}, {0.1, 1.0, 0.3}};
  hc::ActuatorModel m(std::make_unique<hc::ModifiedPiModel>(p));
  m.configure(kDt);
  return m;
}

// The record's input: a 2 Hz triangle with a step every half second on top, n samples.
std::vector<double> triangle_with_steps(std::size_t n) {
  std::vector<double> u(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = kDt * static_cast<double>(k);
    const double phase = std::fmod(2.0 * t, 1.0);
    const double tri = phase < 0.5 ? 2.0 * phase : 2.0 - 2.0 * phase;
    u[k] = 10.0 + 70.0 * tri + (std::fmod(t, 1.0) < 0.5 ? 0.0 : 8.0);
  }
  return u;
}

void BM_DiagnoseModeAndDelay(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const std::vector<double> u = triangle_with_steps(n);
  std::vector<double> t(n);
  for (std::size_t k = 0; k < n; ++k) t[k] = kDt * static_cast<double>(k);
  // The baseline with the mode and the delay added, plus 0.02 um of noise.
  hc::ActuatorModel truth = baseline();
  truth.set_dynamics(hc::DynamicsParameters{3000.0, 0.08});
  truth.set_delay(2.0 * kDt);
  truth.configure(kDt);
  std::vector<double> y = truth.simulate(u, kDt);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.02);
  for (double& v : y) v += noise(rng);
  hc::DiagnosisOptions o;
  o.baseline = baseline();
  std::string cause;
  for (auto _ : state) {
    const hc::Diagnosis d = hc::diagnose(t, u, y, o);
    cause = std::string(hc::to_string(d.cause));
  }
  state.SetLabel("cause " + cause);
}
BENCHMARK(BM_DiagnoseModeAndDelay)->Arg(100000)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
