// ns per sample of each model's step and of the inverses, at n = 10, 50, 200 plays
// (modified PI: n plays and 2m+1 = n/5 + 1 dead zones); the Preisach model at n x n cells.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/drive_planner.hpp"
#include "hystbench/compensation/dynamics_inversion.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/preisach_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;

namespace {

std::vector<double> input_signal() {
  std::mt19937_64 rng(1);
  return hystbench::testing::random_reversal_signal(rng, 4096, 0.0, 150.0);
}

hc::ActuatorModel make_model(const std::string& kind, int n) {
  std::mt19937_64 rng(static_cast<unsigned>(n));
  auto mpi = hystbench::testing::random_mpi(rng, n, n / 10, 150.0);
  std::unique_ptr<hc::HysteresisModel> h;
  if (kind == "pi") {
    h = std::make_unique<hc::PiModel>(mpi.play);
  } else if (kind == "mpi") {
    h = std::make_unique<hc::ModifiedPiModel>(mpi);
  } else if (kind == "preisach") {
    std::uniform_real_distribution<double> d(0.0, 1e-4);
    hc::PreisachParameters p{0.0,
                             150.0,
                             static_cast<std::size_t>(n),
                             std::vector<double>(hc::PreisachModel::cell_count(n)),
                             0.05,
                             0.0};
    for (double& x : p.densities) x = d(rng);
    h = std::make_unique<hc::PreisachModel>(p);
  } else if (kind == "rpi") {
    h = std::make_unique<hc::RateDependentPiModel>(
        hc::RateDependentPiParameters{mpi, std::vector<double>(n, 1e-6), 1e4}, 1e-4);
  } else {
    hc::CoupledPlayParameters p;
    for (int i = 0; i < n; ++i) {
      const double r = mpi.play.thresholds[i];
      p.r.push_back(r), p.ra.push_back(0.5 * r), p.rb.push_back(r), p.rc.push_back(1.5 * r);
      p.weights.push_back(i == 0 ? 0.3 : 0.01);
    }
    h = std::make_unique<hc::CoupledPlayPiModel>(p);
  }
  hc::ActuatorModel m(std::move(h));
  m.input_min = 0.0;
  m.input_max = 150.0;
  m.configure(1e-4);
  m.reset(0.0);
  return m;
}

void model_step(benchmark::State& state, const std::string& kind) {
  auto m = make_model(kind, static_cast<int>(state.range(0)));
  const auto u = input_signal();
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(m.step(u[k]));
    k = (k + 1) & 4095;
  }
  state.SetLabel("ns/sample = time");
}

void inverse_step(benchmark::State& state, const std::string& kind, hc::InverseKind inv) {
  auto m = make_model(kind, static_cast<int>(state.range(0)));
  // Reachable references: the model's own response.
  auto copy = m;
  std::vector<double> y;
  for (double u : input_signal()) y.push_back(copy.step(u));
  auto inverse = hc::make_inverse(m, inv);
  inverse->reset(0.0);
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(inverse->step(y[k]));
    k = (k + 1) & 4095;
  }
}

// The feedforward's per-tick work with a model holding delay and dynamics: the
// dynamics inversion's target from three previewed reference values, then the analytic MPI
// inverse (the loop samples the generator three times; that is the generator's cost, not this).
void dynamic_feedforward_step(benchmark::State& state) {
  auto m = make_model("mpi", static_cast<int>(state.range(0)));
  m.set_delay(2e-4);
  m.set_dynamics(hc::DynamicsParameters{3000.0, 0.08});
  m.configure(1e-4);
  m.reset(0.0);
  const hc::DynamicsInversion inversion(m, 1e-4);
  auto copy = m;
  copy.set_delay(0.0);
  copy.set_dynamics(std::nullopt);
  copy.configure(1e-4);
  std::vector<double> y;
  for (double u : input_signal()) y.push_back(copy.step(u));
  copy.reset(0.0);
  auto inverse = hc::make_inverse(copy);
  inverse->reset(0.0);
  std::size_t k = 0;
  for (auto _ : state) {
    const double target = inversion.target(y[k], y[(k + 1) & 4095], y[(k + 2) & 4095]);
    benchmark::DoNotOptimize(inverse->step(target));
    k = (k + 1) & 4095;
  }
  state.SetLabel("ns/tick = time");
}

// Planning the drive of a 10 Hz sine (1 s at 10 kHz, 10 000 samples) on an rpi of n plays:
// the time a track run's start waits for its planned feedforward. Per sample = time / 10 000.
void plan_drive_10hz(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::mt19937_64 rng(static_cast<unsigned>(n));
  auto mpi = hystbench::testing::random_mpi(rng, n, n / 10, 150.0);
  std::vector<double> c;
  for (int i = 0; i < n; ++i) c.push_back(2e-5 * i / n);
  hc::ActuatorModel m(
      std::make_unique<hc::RateDependentPiModel>(hc::RateDependentPiParameters{mpi, c, 1e4}, 1e-4));
  m.input_min = 0.0;
  m.input_max = 150.0;
  m.configure(1e-4);
  m.reset(0.0);
  // A reachable reference: the model's output for a 10 Hz input sine over 15-135 V.
  std::vector<double> targets;
  auto shaper = m;
  for (int k = 0; k < 10000; ++k)
    targets.push_back(shaper.step(75.0 - 60.0 * std::cos(2.0 * M_PI * 10.0 * k * 1e-4)));
  for (auto _ : state) benchmark::DoNotOptimize(hc::plan_drive(m, 0.0, {}, targets).rms);
  state.SetLabel("10 000 samples");
}

}  // namespace

BENCHMARK(plan_drive_10hz)->Arg(10)->Arg(50)->Unit(benchmark::kMillisecond);
BENCHMARK(dynamic_feedforward_step)->Arg(10)->Arg(50)->Arg(200);
BENCHMARK_CAPTURE(model_step, pi, std::string("pi"))->Arg(10)->Arg(50)->Arg(200);
BENCHMARK_CAPTURE(model_step, mpi, std::string("mpi"))->Arg(10)->Arg(50)->Arg(200);
BENCHMARK_CAPTURE(model_step, cpi, std::string("cpi"))->Arg(10)->Arg(50)->Arg(200);
BENCHMARK_CAPTURE(model_step, rpi, std::string("rpi"))->Arg(10)->Arg(50)->Arg(200);
BENCHMARK_CAPTURE(model_step, preisach, std::string("preisach"))->Arg(10)->Arg(30);
BENCHMARK_CAPTURE(inverse_step, preisach_numeric, std::string("preisach"),
                  hc::InverseKind::kNumeric)
    ->Arg(10)
    ->Arg(30);
BENCHMARK_CAPTURE(inverse_step, pi_analytic, std::string("pi"), hc::InverseKind::kAnalytic)
    ->Arg(10)
    ->Arg(50)
    ->Arg(200);
BENCHMARK_CAPTURE(inverse_step, mpi_analytic, std::string("mpi"), hc::InverseKind::kAnalytic)
    ->Arg(10)
    ->Arg(50)
    ->Arg(200);
BENCHMARK_CAPTURE(inverse_step, mpi_multiplicative, std::string("mpi"),
                  hc::InverseKind::kMultiplicative)
    ->Arg(10)
    ->Arg(50)
    ->Arg(200);
BENCHMARK_CAPTURE(inverse_step, cpi_numeric, std::string("cpi"), hc::InverseKind::kNumeric)
    ->Arg(10)
    ->Arg(50)
    ->Arg(200);
BENCHMARK_CAPTURE(inverse_step, rpi_numeric, std::string("rpi"), hc::InverseKind::kNumeric)
    ->Arg(10)
    ->Arg(50)
    ->Arg(200);
