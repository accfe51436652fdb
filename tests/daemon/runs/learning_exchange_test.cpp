// The hand-over between the loop and the learner, ticked by hand: trial 0 plays the
// compensator's drive; a drive offered before a period begins is that period's trial; a period
// with none replays the last drive and is not a trial; the drive offered as the last ends the
// run after its period; the loop owes a wait only for a drive the learner owes.
#include "hystbench/daemon/runs/learning_exchange.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

namespace hd = hystbench::daemon;

namespace {

constexpr std::size_t kPeriod = 4;
constexpr std::uint64_t kFirst = 10;

// Ticks one period from tick k; the drive played (NaN where the compensator's) and whether the
// run ends after it. The error recorded is 100 x period index + phase.
struct Played {
  std::vector<double> drive;
  bool ends = false;
};
Played tick_period(hd::LearningExchange& x, std::uint64_t k) {
  Played p;
  for (std::size_t i = 0; i < kPeriod; ++i) {
    const std::size_t j = x.begin_tick(k + i);
    EXPECT_EQ(j, i);
    double u = -1.0;
    u = 1000.0 + static_cast<double>(j);  // the compensator's
    (void)x.learned(j, u);
    p.drive.push_back(u);
    const std::uint64_t trial = (k - kFirst) / kPeriod;  // the error names its trial
    p.ends = x.end_tick(j, u, 1000.0 + static_cast<double>(j),
                        100.0 * static_cast<double>(trial) + static_cast<double>(j));
  }
  return p;
}

}  // namespace

TEST(LearningExchange, TrialsAreThePeriodsThatBeginWithANewDrive) {
  hd::LearningExchange x(kPeriod, kFirst);
  std::vector<double> u, c, e;
  std::uint64_t trial = 99;
  EXPECT_FALSE(x.take_trial(u, c, e, trial));
  // Trial 0: the compensator's drive, recorded.
  Played p = tick_period(x, kFirst);
  EXPECT_EQ(p.drive, std::vector<double>({1000, 1001, 1002, 1003}));
  EXPECT_FALSE(p.ends);
  EXPECT_EQ(x.trials_played(), 1u);
  // The learner owes the next period a drive: on the simulated clock the loop waits.
  EXPECT_TRUE(x.owed(kFirst + kPeriod));
  EXPECT_FALSE(x.owed(kFirst + kPeriod + 1));  // only at a period's start
  ASSERT_TRUE(x.take_trial(u, c, e, trial));
  EXPECT_EQ(trial, 0u);
  EXPECT_EQ(u, std::vector<double>({1000, 1001, 1002, 1003}));
  EXPECT_EQ(e, std::vector<double>({0, 1, 2, 3}));
  EXPECT_FALSE(x.take_trial(u, c, e, trial));  // taken once
  ASSERT_TRUE(x.offer({1, 2, 3, 4}, false));
  EXPECT_FALSE(x.offer({5, 6, 7, 8}, false));  // the loop has not taken the one before
  EXPECT_FALSE(x.owed(kFirst + kPeriod));
  // Trial 1 plays the offered drive.
  p = tick_period(x, kFirst + kPeriod);
  EXPECT_EQ(p.drive, std::vector<double>({1, 2, 3, 4}));
  ASSERT_TRUE(x.take_trial(u, c, e, trial));
  EXPECT_EQ(trial, 1u);
  EXPECT_EQ(e, std::vector<double>({100, 101, 102, 103}));
  // Nothing offered in time (the wall clock): the period replays the drive, is not a trial.
  p = tick_period(x, kFirst + 2 * kPeriod);
  EXPECT_EQ(p.drive, std::vector<double>({1, 2, 3, 4}));
  EXPECT_EQ(x.stale_periods(), 1u);
  EXPECT_FALSE(x.take_trial(u, c, e, trial));
  // The last drive: its period is trial 2 and the run ends after it; nothing more is owed.
  ASSERT_TRUE(x.offer({9, 9, 9, 9}, true));
  p = tick_period(x, kFirst + 3 * kPeriod);
  EXPECT_EQ(p.drive, std::vector<double>({9, 9, 9, 9}));
  EXPECT_TRUE(p.ends);
  std::uint64_t first_tick = 0;
  ASSERT_TRUE(x.take_trial(u, c, e, trial, &first_tick));
  EXPECT_EQ(trial, 2u);
  EXPECT_EQ(first_tick, kFirst + 3 * kPeriod);  // after the stale period: the run tick it began
  EXPECT_FALSE(x.owed(kFirst + 4 * kPeriod));
}

// A learner that gives up owes nothing: the loop plays on with the last drive it took.
TEST(LearningExchange, ALearnerThatGivesUpOwesNothing) {
  hd::LearningExchange x(kPeriod, kFirst);
  (void)tick_period(x, kFirst);
  EXPECT_TRUE(x.owed(kFirst + kPeriod));
  x.give_up();
  EXPECT_FALSE(x.owed(kFirst + kPeriod));
  const Played p = tick_period(x, kFirst + kPeriod);
  EXPECT_EQ(p.drive, std::vector<double>({1000, 1001, 1002, 1003}));
  EXPECT_FALSE(p.ends);
}

TEST(LearningExchange, ADriveLearnedBeforeIsTrialZeroAndTheLearnerOwesTheNext) {
  hd::LearningExchange x(kPeriod, kFirst);
  EXPECT_FALSE(x.start_from({1, 2, 3}, {}, false));  // another period's drive
  ASSERT_TRUE(x.start_from({7, 8, 9, 10}, {}, false));
  EXPECT_FALSE(x.start_from({7, 8, 9, 10}, {}, false));  // once, before the run
  // It plays the period before trial 0 too, and nothing earlier.
  double u = 0.0;
  EXPECT_FALSE(x.lead_in(kFirst - kPeriod - 1, u));
  std::vector<double> lead;
  for (std::uint64_t k = kFirst - kPeriod; k < kFirst; ++k) {
    ASSERT_TRUE(x.lead_in(k, u));
    lead.push_back(u);
  }
  EXPECT_EQ(lead, std::vector<double>({7, 8, 9, 10}));
  Played p = tick_period(x, kFirst);
  EXPECT_EQ(p.drive, std::vector<double>({7, 8, 9, 10}));
  EXPECT_FALSE(p.ends);
  // Trial 0 was handed over and nothing offered for trial 1 yet.
  EXPECT_TRUE(x.owed(kFirst + kPeriod));
  std::vector<double> taken, c, e;
  std::uint64_t trial = 99;
  ASSERT_TRUE(x.take_trial(taken, c, e, trial));
  EXPECT_EQ(trial, 0u);
  EXPECT_EQ(taken, std::vector<double>({7, 8, 9, 10}));
  ASSERT_TRUE(x.offer({1, 1, 1, 1}, true));
  EXPECT_FALSE(x.owed(kFirst + kPeriod));
  p = tick_period(x, kFirst + kPeriod);
  EXPECT_EQ(p.drive, std::vector<double>({1, 1, 1, 1}));
  EXPECT_TRUE(p.ends);
}

TEST(LearningExchange, AReplayOfALearnedDriveEndsAfterTrialZero) {
  hd::LearningExchange x(kPeriod, kFirst);
  double u = 0.0;
  EXPECT_FALSE(x.lead_in(kFirst - 1, u));               // nothing learned before: the compensator's
  EXPECT_DOUBLE_EQ(x.target_offset(kFirst, 3.0), 3.0);  // and the run's tare
  ASSERT_TRUE(x.start_from({7, 8, 9, 10}, {}, true));
  const Played p = tick_period(x, kFirst);
  EXPECT_EQ(p.drive, std::vector<double>({7, 8, 9, 10}));
  EXPECT_TRUE(p.ends);
  EXPECT_FALSE(x.owed(kFirst + kPeriod));
}

// The compensator's feedforward moved by -0.5 since the drive was learned: the drive moves
// with it, in the lead-in and in trial 0, and the trial hands the compensator's own over.
TEST(LearningExchange, ADriveLearnedBeforeMovesWithTheCompensator) {
  hd::LearningExchange x(kPeriod, kFirst);
  EXPECT_FALSE(x.start_from({7, 8, 9, 10}, {1, 2}, true));  // another period's compensator
  ASSERT_TRUE(x.start_from({7, 8, 9, 10}, {1000.5, 1001.5, 1002.5, 1003.5}, true));
  double u = 1000.0;  // the compensator's at phase 0
  ASSERT_TRUE(x.lead_in(kFirst - kPeriod, u));
  EXPECT_DOUBLE_EQ(u, 6.5);
  // The compensator's target takes off the run's tare; the lead-in's second half measures the
  // reading 0.1 above the reference, which trial 0 on takes off too.
  EXPECT_DOUBLE_EQ(x.target_offset(kFirst - kPeriod, 3.0), 3.0);
  for (std::uint64_t k = kFirst - kPeriod; k < kFirst; ++k) {
    x.lead_in_error(k, k < kFirst - kPeriod / 2 ? 5.0 : -0.1, 0.0);  // the first half: the start
  }
  EXPECT_DOUBLE_EQ(x.target_offset(kFirst - 1, 3.0), 3.0);
  EXPECT_DOUBLE_EQ(x.target_offset(kFirst, 3.0), 3.1);
  const Played p = tick_period(x, kFirst);
  EXPECT_EQ(p.drive, std::vector<double>({6.5, 7.5, 8.5, 9.5}));
  std::vector<double> played, c, e;
  std::uint64_t trial = 99;
  ASSERT_TRUE(x.take_trial(played, c, e, trial));
  EXPECT_EQ(played, p.drive);
  EXPECT_EQ(c, std::vector<double>({1000, 1001, 1002, 1003}));
}

// A lead-in of three periods (a fast sine's): the drive learned before plays each at its phase,
// and the offset is the last period's mean error, whole; the periods before it are the start.
TEST(LearningExchange, ALeadInOfSeveralPeriodsMeasuresTheOffsetOnItsLastWhole) {
  constexpr std::uint64_t first = 100;
  hd::LearningExchange x(kPeriod, first, 3);
  ASSERT_TRUE(x.start_from({7, 8, 9, 10}, {}, true));
  double u = 0.0;
  EXPECT_FALSE(x.lead_in(first - 3 * kPeriod - 1, u));  // before the lead-in
  int played = 0;
  for (std::uint64_t k = first - 3 * kPeriod; k < first; ++k) {
    ASSERT_TRUE(x.lead_in(k, u)) << k;
    EXPECT_DOUBLE_EQ(u, 7.0 + static_cast<double>(k % kPeriod)) << k;  // 100 is phase 0
    x.lead_in_error(k, k < first - kPeriod ? 5.0 : (k % 2 == 0 ? -0.3 : 0.1), 0.0);
    ++played;
  }
  EXPECT_EQ(played, 12);
  EXPECT_DOUBLE_EQ(x.lead_in_offset(), 0.1);
  EXPECT_DOUBLE_EQ(x.target_offset(first, 3.0), 3.1);
}

// A lead-in that may last 200 periods (lead_in_plan), following the output's offset every 2
// periods, ending within 0.05 of the offset 1.0 the drive was learned at, or when at the pace it
// came closer over the last `stall_steps` follow steps it would not come within it before the
// longest. The actuator's offset is `offset(k)`; the target takes off the tare (the offset at the
// run's start) and what the lead-in followed, so a lead-in tick's error (reference - reading) is
// what the target takes off less the offset.
hd::LearningLeadIn lead_in_plan(std::size_t stall_steps = 5, double settled = 0.0) {
  hd::LearningLeadIn l;
  l.learned_offset = 1.0;
  l.tolerance = 0.05;
  l.follow_periods = 2;
  l.stall_steps = stall_steps;
  l.settled = settled;
  return l;
}
struct LeadInRun {
  std::uint64_t played = 0;
  std::uint64_t first_scored = 0;
  hd::LearningExchange::LeadInEnd end{};
  double target_at_first = 0.0;
};
template <typename Offset>
LeadInRun run_lead_in(Offset offset, std::size_t stall_steps = 5) {
  constexpr std::uint64_t first = 1000;
  hd::LearningExchange x(kPeriod, first, 200);
  x.follow_offset(3, lead_in_plan(stall_steps));
  EXPECT_TRUE(x.start_from({7, 8, 9, 10}, {}, true));
  const double tare = offset(first - 200 * kPeriod);
  LeadInRun r;
  double u = 0.0;
  for (std::uint64_t k = first - 200 * kPeriod; x.lead_in(k, u); ++k) {
    EXPECT_DOUBLE_EQ(u, 7.0 + static_cast<double>(k % kPeriod)) << k;
    x.lead_in_error(k, x.target_offset(k, tare) - offset(k), tare);
    ++r.played;
  }
  r.first_scored = x.first_scored_tick();
  r.end = x.lead_in_end();
  r.target_at_first = x.target_offset(r.first_scored, tare);
  EXPECT_EQ(x.lead_in_played() * kPeriod, r.played);
  return r;
}

// The offset is the learned one: the lead-in is its minimum, as without following.
TEST(LearningExchange, ALeadInAtTheLearnedOffsetIsItsShortest) {
  const LeadInRun r = run_lead_in([](std::uint64_t) { return 1.02; });
  EXPECT_EQ(r.played, 3 * kPeriod);
  EXPECT_EQ(r.end, hd::LearningExchange::LeadInEnd::kOffsetReached);
  EXPECT_EQ(r.first_scored, 1000 - 197 * kPeriod);
  EXPECT_NEAR(r.target_at_first, 1.02, 1e-12);
}

// The offset starts 0.5 off and creeps toward the learned one: the lead-in follows it and ends
// once it is within the tolerance, its target the actuator's offset.
TEST(LearningExchange, ALeadInFollowsTheOffsetUntilItReachesTheLearnedOne) {
  const auto creep = [](std::uint64_t k) {
    return 1.0 - 0.5 * std::exp(-static_cast<double>(k - 200) / 30.0);
  };
  const LeadInRun r = run_lead_in(creep);
  EXPECT_EQ(r.end, hd::LearningExchange::LeadInEnd::kOffsetReached);
  EXPECT_GT(r.played, 3 * kPeriod);
  EXPECT_LT(r.played, 200 * kPeriod);
  EXPECT_EQ(r.played % kPeriod, 0u);
  EXPECT_NEAR(creep(200 + r.played - kPeriod), 1.0, 0.05 + 1e-9);  // a period before its end
  EXPECT_NEAR(r.target_at_first, creep(200 + r.played), 0.01);
}

// An offset that stays 0.5 off (a drift, not creep): the lead-in stops once following it
// brings it no closer.
TEST(LearningExchange, ALeadInStopsWhenTheOffsetComesNoCloser) {
  const LeadInRun r = run_lead_in([](std::uint64_t) { return 0.5; });
  EXPECT_EQ(r.end, hd::LearningExchange::LeadInEnd::kOffsetStalled);
  EXPECT_LE(r.played, (3 + 2 * 5 + 1) * kPeriod);
  EXPECT_NEAR(r.target_at_first, 0.5, 1e-12);
}

// An offset 2 off that moves toward the learned one at a pace that would reach it only after
// the longest lead-in: it ends when its pace shows that. Where the pace is not checked, the
// lead-in is its longest.
TEST(LearningExchange, ALeadInEndsAtItsLongest) {
  const auto slow = [](std::uint64_t k) {
    return -1.0 + 0.006 * static_cast<double>(k - 200) / kPeriod;
  };
  const LeadInRun paced = run_lead_in(slow);
  EXPECT_EQ(paced.end, hd::LearningExchange::LeadInEnd::kOffsetStalled);
  EXPECT_LE(paced.played, (3 + 2 * 5 + 1) * kPeriod);
  const LeadInRun r = run_lead_in(slow, 1000);
  EXPECT_EQ(r.end, hd::LearningExchange::LeadInEnd::kLongest);
  EXPECT_EQ(r.played, 200 * kPeriod);
  EXPECT_EQ(r.first_scored, 1000u);
}

// The actuator answers a move of the target by 1.25x the move (the model's gain there is not the
// actuator's), its offset 0.04 from the tare's, within the tolerance at once. Ended there, the
// last period's mean taken off would leave a quarter of it at trial 0. Settling, the lead-in
// follows the error until a step's mean is within `settled`, and trial 0 starts well within it;
// also where the pace is checked every step (following moves the offset away from the learned
// one: the settling's own steps bound it, not the stall).
TEST(LearningExchange, ALeadInSettlesTheErrorWhereTheActuatorAnswersAMoveByMore) {
  auto lead_in = [](double settled, std::size_t stall_steps = 5) {
    constexpr std::uint64_t first = 1000;
    constexpr double kGain = 1.25, kTare = 1.0, kOffset = 1.04;
    hd::LearningExchange x(kPeriod, first, 200);
    x.follow_offset(3, lead_in_plan(stall_steps, settled));
    EXPECT_TRUE(x.start_from({7, 8, 9, 10}, {}, true));
    auto error_at = [&](std::uint64_t k) {
      return kGain * (x.target_offset(k, kTare) - kTare) + kTare - kOffset;
    };
    double u = 0.0;
    for (std::uint64_t k = first - 200 * kPeriod; x.lead_in(k, u); ++k) {
      x.lead_in_error(k, error_at(k), kTare);
    }
    EXPECT_EQ(x.lead_in_end(), hd::LearningExchange::LeadInEnd::kOffsetReached);
    return std::pair{error_at(x.first_scored_tick()), x.lead_in_played()};
  };
  const auto [unsettled, shortest] = lead_in(0.0);
  EXPECT_EQ(shortest, 3u);
  EXPECT_NEAR(unsettled, 0.01, 1e-9);
  const hd::LearningLeadIn defaults;
  const auto [left, played] = lead_in(0.005);
  EXPECT_LE(std::abs(left), 0.005 / 4);
  EXPECT_GT(played, 3u);
  EXPECT_LE(played, 3 + 2 * (defaults.settle_steps + 1));
  const auto [left_paced, played_paced] = lead_in(0.005, 1);
  EXPECT_DOUBLE_EQ(left_paced, left);
  EXPECT_EQ(played_paced, played);
}

// Two axes of a stage: x's offset is its learned one at once, y's creeps toward its own. Alone,
// x's lead-in ends at its minimum while y's goes on; deciding together, both end at the first
// period where y's would, their trial 0 at one tick, and x follows its offset until then.
TEST(LearningExchange, AStagesLeadInsEndTogetherWhereEveryAxisWould) {
  constexpr std::uint64_t first = 1000;
  const auto creep = [](std::uint64_t k) {
    return 1.0 - 0.5 * std::exp(-static_cast<double>(k - 200) / 30.0);
  };
  const auto settled = [](std::uint64_t) { return 1.02; };
  auto lead_in = [&](hd::LearningExchange::LeadInTogether* together) {
    std::vector<std::unique_ptr<hd::LearningExchange>> axes;
    for (int a = 0; a < 2; ++a) {
      axes.push_back(std::make_unique<hd::LearningExchange>(kPeriod, first, 200));
      axes.back()->follow_offset(3, lead_in_plan());
      EXPECT_TRUE(axes.back()->start_from({7, 8, 9, 10}, {}, true));
      axes.back()->decide_together(together);
    }
    const double tare[2] = {settled(200), creep(200)};
    for (std::uint64_t k = first - 200 * kPeriod; k < first; ++k) {
      for (int a = 0; a < 2; ++a) {
        double u = 0.0;
        if (!axes[a]->lead_in(k, u)) continue;
        const double offset = a == 0 ? settled(k) : creep(k);
        axes[a]->lead_in_error(k, axes[a]->target_offset(k, tare[a]) - offset, tare[a]);
      }
    }
    return axes;
  };
  const auto alone = lead_in(nullptr);
  EXPECT_EQ(alone[0]->lead_in_played(), 3u);
  EXPECT_GT(alone[1]->lead_in_played(), 3u);
  EXPECT_LT(alone[1]->lead_in_played(), 200u);

  hd::LearningExchange::LeadInTogether together;
  together.axes = 2;
  const auto both = lead_in(&together);
  EXPECT_EQ(both[0]->first_scored_tick(), both[1]->first_scored_tick());
  EXPECT_EQ(both[1]->lead_in_played(), alone[1]->lead_in_played());
  EXPECT_EQ(both[0]->lead_in_end(), hd::LearningExchange::LeadInEnd::kOffsetReached);
  // x measured its offset on its own last period, as an axis alone does.
  EXPECT_NEAR(both[0]->target_offset(both[0]->first_scored_tick(), settled(200)), 1.02, 1e-9);
}

// A drive learned before moves by how far the compensator's feedforward moved: from its twin's
// at this tick where one steps beside it (fed the targets at the offset the drive was learned
// at), else from the feedforward saved with the drive.
TEST(LearningExchange, ADriveLearnedBeforeMovesFromTheTwinWhereOneStepsBesideIt) {
  hd::LearningExchange x(kPeriod, kFirst);
  ASSERT_TRUE(x.start_from({7, 8, 9, 10}, {1000.5, 1001.5, 1002.5, 1003.5}, true));
  double u = 1000.0;  // the compensator's at phase 0
  ASSERT_TRUE(x.lead_in(kFirst - kPeriod, u, 999.0));
  EXPECT_DOUBLE_EQ(u, 8.0);  // 7 + (1000 - 999)
  u = 1000.0;
  ASSERT_TRUE(x.lead_in(kFirst - kPeriod, u));
  EXPECT_DOUBLE_EQ(u, 6.5);  // 7 + (1000 - 1000.5)
}
