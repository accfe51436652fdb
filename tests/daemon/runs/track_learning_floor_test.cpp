// The bench's floor a track --learn run measures on trials 0 and 1 (the same drive), against a
// loop ticked by hand whose errors are scripted: the sensor's noise, and in trial 0 the start
// from rest still settling (a straight line, the fundamental and the second harmonic moving
// toward the orbit the loop repeats). The floor is the noise's, not the settling's; over a
// short trial (20 samples) the harmonics are kept and the floor holds them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "hystbench/daemon/runs/learning_exchange.hpp"
#include "runs/details/track_learning.hpp"
#include "support/random_models.hpp"

namespace hd = hystbench::daemon;
namespace hc = hystbench::compensation;

namespace {

constexpr double kRate = 10000.0;
constexpr double kNoiseUm = 0.005;  // the sensor's, rms

// The floor [µm] the learner measured over trials of `period` samples: trial 0's error the
// noise plus the settling (`settling` µm at the fundamental, half of it at the second harmonic,
// and a line of that much over the trial), trial 1's the noise alone.
double measured_floor(std::size_t period, double settling) {
  std::mt19937_64 rng(3);
  const hc::ActuatorModel model = hystbench::testing::random_mpi_actuator(rng, 8, 2, 10.0, 1e-4);
  hd::LearningExchange x(period, 0);
  hd::details::LearningRequest r;
  r.trials = 2;
  r.range_um = 10.0;
  r.frequency_hz = kRate / static_cast<double>(period);
  r.reference = "sine";
  r.rate_hz = kRate;
  r.max_um = 10.0;
  hc::LearningOptions o;
  o.dt = 1.0 / kRate;
  o.u_min = 0.0;
  o.u_max = 10.0;
  hd::details::TrackLearning learning(model, x, r, o);
  std::normal_distribution<double> noise(0.0, kNoiseUm);
  std::uint64_t k = 0;
  for (int t = 0; t < 2; ++t) {
    for (std::size_t i = 0; i < period; ++i, ++k) {
      const std::size_t j = x.begin_tick(k);
      double u = 5.0;
      (void)x.learned(j, u);
      const double phase =
          2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(period);
      const double start = t == 0
                               ? settling * (std::sin(phase + 0.4) + 0.5 * std::cos(2.0 * phase) +
                                             static_cast<double>(j) / static_cast<double>(period))
                               : 0.0;
      (void)x.end_tick(j, u, 5.0, noise(rng) + start);
    }
    (void)learning.poll();
  }
  return learning.result()["floor"]["rms_error_um"].get<double>();
}

}  // namespace

TEST(TrackLearningFloor, IsTheNoiseNotTheStartStillSettling) {
  // 50 Hz at 10 kHz (200 samples): the settling, 3x the noise, is left out.
  const double settled = measured_floor(200, 0.0);
  const double settling = measured_floor(200, 3.0 * kNoiseUm);
  EXPECT_NEAR(settled, kNoiseUm, 0.2 * kNoiseUm);
  EXPECT_NEAR(settling, kNoiseUm, 0.2 * kNoiseUm);
  // 500 Hz (20 samples): two harmonics are much of the band; they stay in the floor.
  const double short_trial = measured_floor(20, 6.0 * kNoiseUm);
  EXPECT_GT(short_trial, 1.5 * kNoiseUm);
}
