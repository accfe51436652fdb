// The bench's floor a track --learn run measures on trials 0 and 1 (the same drive), against a
// loop ticked by hand whose errors are scripted: the sensor's noise, and in trial 0 the start
// from rest still settling (a straight line, the fundamental and the second harmonic moving
// toward the orbit the loop repeats). The floor is the noise's, not the settling's; over a
// short trial (20 samples) the harmonics are kept and the floor holds them. A trial that reaches
// the floor has its drive played again, and that pair measures the floor anew: learning goes on
// where it is lower than trials 0 and 1 showed, and stops where it held.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "hystbench/daemon/runs/learning_exchange.hpp"
#include "runs/details/track_learning.hpp"
#include "support/random_models.hpp"

namespace hd = hystbench::daemon;
namespace hc = hystbench::compensation;

namespace {

using TrackLearningFloorLimits = hd::details::TrackLearning;
constexpr double kRate = 10000.0;
constexpr double kNoiseUm = 0.005;  // the sensor's, rms

// A learner of `trials` learned trials of `period` samples, a 10 µm sine at 10 kHz, on the loop
// side of its own exchange (ticked by hand).
struct HandTickedLearning {
  HandTickedLearning(std::size_t period, std::size_t trials, std::uint64_t seed)
      : x(period, 0), learning(model(seed), x, request(period, trials), options()) {}
  static hc::ActuatorModel model(std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    return hystbench::testing::random_mpi_actuator(rng, 8, 2, 10.0, 1e-4);
  }
  static hd::details::LearningRequest request(std::size_t period, std::size_t trials) {
    hd::details::LearningRequest r;
    r.trials = trials;
    r.range_um = 10.0;
    r.frequency_hz = kRate / static_cast<double>(period);
    r.reference = "sine";
    r.rate_hz = kRate;
    r.max_um = 10.0;
    return r;
  }
  static hc::LearningOptions options() {
    hc::LearningOptions o;
    o.dt = 1.0 / kRate;
    o.u_min = 0.0;
    o.u_max = 10.0;
    return o;
  }
  hd::LearningExchange x;
  hd::details::TrackLearning learning;
};

// The floor [µm] the learner measured over trials of `period` samples: trial 0's error the
// noise plus the settling (`settling` µm at the fundamental, half of it at the second harmonic,
// and a line of that much over the trial), trial 1's the noise alone.
double measured_floor(std::size_t period, double settling) {
  HandTickedLearning h(period, 2, 3);
  hd::LearningExchange& x = h.x;
  hd::details::TrackLearning& learning = h.learning;
  std::mt19937_64 rng(3);
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

// A learning run of `trials` learned trials of 200 samples over a scripted loop: trial n's error
// is a repeatable sine of repeatable(m) µm, m the drives played before that differ from this one
// (a drive played again repeats its error), plus noise of noise(n) µm rms. Returns the result.
nlohmann::json scripted_run(std::size_t trials, const std::function<double(std::size_t)>& noise,
                            const std::function<double(std::size_t)>& repeatable) {
  constexpr std::size_t kPeriod = 200;
  HandTickedLearning h(kPeriod, trials, 5);
  hd::LearningExchange& x = h.x;
  hd::details::TrackLearning& learning = h.learning;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::uint64_t k = 0;
  std::size_t m = 0;
  std::vector<double> before;
  for (std::size_t t = 0; t < trials + 2; ++t) {
    bool last = false;
    for (std::size_t i = 0; i < kPeriod; ++i, ++k) {
      const std::size_t j = x.begin_tick(k);
      if (j == 0) {
        // The drive this trial plays, whole: another than the trial before's moves the error on.
        std::vector<double> drive(kPeriod, 5.0);
        for (std::size_t jj = 0; jj < kPeriod; ++jj) (void)x.learned(jj, drive[jj]);
        if (t > 0 && drive != before) ++m;
        before = drive;
      }
      double u = 5.0;
      (void)x.learned(j, u);
      const double phase =
          2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(kPeriod);
      const double e = std::sqrt(2.0) * repeatable(m) * std::sin(phase) + noise(t) * unit(rng);
      last = x.end_tick(j, u, 5.0, e);
    }
    (void)learning.poll();
    if (last) break;
  }
  return learning.result();
}

std::vector<std::string> drives(const nlohmann::json& result) {
  std::vector<std::string> out;
  for (const auto& t : result["trials"]) out.push_back(t["drive"].get<std::string>());
  return out;
}

}  // namespace

TEST(TrackLearningFloor, ATrialAtTheFloorRepeatsItsDriveAndLearnsOnWhereTheFloorWasLower) {
  // Trials 0 and 1 differ by 4x the noise the learned trials show: their floor is too high. The
  // repeatable error halves every trial from 0.1 µm.
  const nlohmann::json l = scripted_run(
      12, [](std::size_t t) { return t < 2 ? 4.0 * kNoiseUm : kNoiseUm; },
      [](std::size_t t) { return 0.1 * std::pow(0.5, static_cast<double>(t)); });
  const std::vector<std::string> d = drives(l);
  ASSERT_GE(d.size(), 6u) << l.dump(2);
  const auto& floor = l["floor"];
  const std::size_t first = floor["trials"][0].get<std::size_t>();
  ASSERT_GE(first, 2u) << l.dump(2);
  EXPECT_EQ(floor["trials"][1].get<std::size_t>(), first + 1);
  EXPECT_EQ(d[first + 1], "repeat");
  EXPECT_NEAR(floor["first_rms_error_um"].get<double>(), 4.0 * kNoiseUm, 0.8 * kNoiseUm);
  EXPECT_NEAR(floor["rms_error_um"].get<double>(), kNoiseUm, 0.2 * kNoiseUm) << l.dump(1);
  // After the repeat the learning went on (the trial was above the new floor).
  ASSERT_GT(d.size(), first + 2);
  EXPECT_EQ(d[first + 2], "learned") << l.dump(2);
}

TEST(TrackLearningFloor, AFloorThatHoldsOnTheRepeatStopsTheLearningWithItsDriveOnceMore) {
  // The same noise throughout: the repeat confirms the floor, the learning stops and the drive
  // plays once more (the repeat settled the actuator), before the trials asked for ran out.
  const nlohmann::json l = scripted_run(
      12, [](std::size_t) { return 2.0 * kNoiseUm; },
      [](std::size_t t) { return 0.1 * std::pow(0.5, static_cast<double>(t)); });
  const std::vector<std::string> d = drives(l);
  const std::size_t first = l["floor"]["trials"][0].get<std::size_t>();
  ASSERT_GE(first, 2u) << l.dump(2);
  ASSERT_EQ(d.size(), first + 3) << l.dump(2);
  EXPECT_EQ(d[first + 1], "repeat");
  EXPECT_EQ(d[first + 2], "best");
  EXPECT_TRUE(l["stopped"].get<bool>());
  EXPECT_TRUE(l["floor"]["reached"].get<bool>());
  EXPECT_NE(l["why"].get<std::string>().find("once more"), std::string::npos) << l["why"];
  // The drive played once more repeated its error.
  ASSERT_TRUE(l.contains("best_replayed")) << l.dump(1);
  EXPECT_EQ(l["best_replayed"]["trial"].get<std::size_t>(), first) << l.dump(1);
  EXPECT_TRUE(l["best_replayed"]["held"].get<bool>()) << l.dump(1);
  EXPECT_FALSE(l["best_replayed"].contains("meaning")) << l.dump(1);
}

TEST(TrackLearningFloor, AGuardThatStopsNamesTheBestTrial) {
  // The repeatable error falls to trial 3's drive, then grows fourfold with each drive: two
  // trials in a row above the best stop the learning, which names trial 3 and plays its drive.
  const nlohmann::json l = scripted_run(
      12, [](std::size_t) { return 0.1 * kNoiseUm; },
      [](std::size_t m) {
        return m <= 2 ? 0.1 * std::pow(0.5, static_cast<double>(m))
                      : 0.025 * std::pow(4.0, static_cast<double>(m - 2));
      });
  EXPECT_TRUE(l["stopped"].get<bool>());
  const std::string why = l["why"].get<std::string>();
  EXPECT_NE(why.find("above the best (trial 3)"), std::string::npos) << l.dump(1);
  EXPECT_EQ(l["best_trial"].get<int>(), 3) << l.dump(1);
  // The scripted loop answers the best drive, played after others, with a new and larger error:
  // the result says its replays did not repeat trial 3's.
  ASSERT_TRUE(l.contains("best_replayed")) << l.dump(1);
  const nlohmann::json& b = l["best_replayed"];
  EXPECT_EQ(b["trial"].get<int>(), 3) << b;
  EXPECT_FALSE(b["held"].get<bool>()) << b;
  ASSERT_FALSE(b["replays_rms_percent"].empty()) << b;
  EXPECT_GT(b["replays_rms_percent"][0].get<double>(),
            TrackLearningFloorLimits::kReplayHeld * b["rms_error_percent"].get<double>())
      << b;
  EXPECT_NE(b.value("meaning", std::string()).find("does not repeat"), std::string::npos) << b;
}

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
