// The hand-over between the loop and the learner, ticked by hand: trial 0 plays the
// compensator's drive; a drive offered before a period begins is that period's trial; a period
// with none replays the last drive and is not a trial; the drive offered as the last ends the
// run after its period; the loop owes a wait only for a drive the learner owes.
#include "hystbench/daemon/learning_exchange.hpp"

#include <gtest/gtest.h>

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
    if (!x.learned(j, u)) u = 1000.0 + static_cast<double>(j);  // the compensator's
    p.drive.push_back(u);
    p.ends = x.end_tick(j, u, 100.0 * static_cast<double>((k - kFirst) / kPeriod) + j);
  }
  return p;
}

}  // namespace

TEST(LearningExchange, TrialsAreThePeriodsThatBeginWithANewDrive) {
  hd::LearningExchange x(kPeriod, kFirst);
  std::vector<double> u, e;
  std::uint64_t trial = 99;
  EXPECT_FALSE(x.take_trial(u, e, trial));
  // Trial 0: the compensator's drive, recorded.
  Played p = tick_period(x, kFirst);
  EXPECT_EQ(p.drive, std::vector<double>({1000, 1001, 1002, 1003}));
  EXPECT_FALSE(p.ends);
  EXPECT_EQ(x.trials_played(), 1u);
  // The learner owes the next period a drive: on the simulated clock the loop waits.
  EXPECT_TRUE(x.owed(kFirst + kPeriod));
  EXPECT_FALSE(x.owed(kFirst + kPeriod + 1));  // only at a period's start
  ASSERT_TRUE(x.take_trial(u, e, trial));
  EXPECT_EQ(trial, 0u);
  EXPECT_EQ(u, std::vector<double>({1000, 1001, 1002, 1003}));
  EXPECT_EQ(e, std::vector<double>({0, 1, 2, 3}));
  EXPECT_FALSE(x.take_trial(u, e, trial));  // taken once
  ASSERT_TRUE(x.offer({1, 2, 3, 4}, false));
  EXPECT_FALSE(x.offer({5, 6, 7, 8}, false));  // the loop has not taken the one before
  EXPECT_FALSE(x.owed(kFirst + kPeriod));
  // Trial 1 plays the offered drive.
  p = tick_period(x, kFirst + kPeriod);
  EXPECT_EQ(p.drive, std::vector<double>({1, 2, 3, 4}));
  ASSERT_TRUE(x.take_trial(u, e, trial));
  EXPECT_EQ(trial, 1u);
  EXPECT_EQ(e, std::vector<double>({100, 101, 102, 103}));
  // Nothing offered in time (the wall clock): the period replays the drive, is not a trial.
  p = tick_period(x, kFirst + 2 * kPeriod);
  EXPECT_EQ(p.drive, std::vector<double>({1, 2, 3, 4}));
  EXPECT_EQ(x.stale_periods(), 1u);
  EXPECT_FALSE(x.take_trial(u, e, trial));
  // The last drive: its period is trial 2 and the run ends after it; nothing more is owed.
  ASSERT_TRUE(x.offer({9, 9, 9, 9}, true));
  p = tick_period(x, kFirst + 3 * kPeriod);
  EXPECT_EQ(p.drive, std::vector<double>({9, 9, 9, 9}));
  EXPECT_TRUE(p.ends);
  ASSERT_TRUE(x.take_trial(u, e, trial));
  EXPECT_EQ(trial, 2u);
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
