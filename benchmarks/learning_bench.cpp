// The iterative learning's update: one trial of a 1 s sine at 10 kHz (10 000 samples) through a
// modified PI of 20 plays and 2 x 2 + 1 dead zones, as track --learn computes it after each trial
// (off the loop thread). Wall time per update. And what learning adds to a tick of the loop: the
// exchange's calls a learning tick makes (the drive played, the trial recorded), with the
// learner's hand-over (taking each trial, offering the next drive) counted in too, per tick.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "hystbench/compensation/iterative_learning.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/daemon/runs/learning_exchange.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;

namespace {

void learning_update(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::mt19937_64 rng(7);
  hc::ActuatorModel model = hystbench::testing::random_mpi_actuator(rng, 20, 2, 150.0, 1e-4);
  model.set_delay(2e-4);
  model.configure(1e-4);
  std::vector<double> drive(n), error(n), next(n);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (std::size_t j = 0; j < n; ++j) {
    const double phase = 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(n);
    drive[j] = 75.0 - 60.0 * std::cos(phase);
    error[j] = 0.2 * std::sin(3.0 * phase) + noise(rng);
  }
  hc::LearningOptions o;
  o.dt = 1e-4;
  o.u_min = 0.0;
  o.u_max = 150.0;
  hc::IterativeLearning learner(model, n, o);
  for (auto _ : state) {
    learner.update(drive, error, 0.5, next);
    benchmark::DoNotOptimize(next.data());
  }
  state.SetLabel("per update, " + std::to_string(n) + " samples");
}

void learning_loop_tick(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  hystbench::daemon::LearningExchange x(n, 0);
  std::vector<double> drive(n), u(n), c(n), e(n);
  for (std::size_t j = 0; j < n; ++j)
    drive[j] = 75.0 + 60.0 * std::sin(0.01 * static_cast<double>(j));
  std::uint64_t k = 0, trial = 0;
  double sum = 0.0;
  for (auto _ : state) {
    const std::size_t j = x.begin_tick(k);
    double u_ff = 75.0;
    x.learned(j, u_ff);
    x.end_tick(j, u_ff, 75.0, 0.01 * u_ff);
    sum += u_ff;
    if (j + 1 == n) {  // the learner's side, here on the same thread
      if (x.take_trial(u, c, e, trial)) x.offer(drive, false);
    }
    ++k;
  }
  benchmark::DoNotOptimize(sum);
  state.SetLabel("per tick, a trial of " + std::to_string(n) + " samples");
}

}  // namespace

BENCHMARK(learning_loop_tick)->Arg(200)->Arg(10000)->Unit(benchmark::kNanosecond);
BENCHMARK(learning_update)->Arg(10000)->Arg(200)->Unit(benchmark::kMillisecond);
