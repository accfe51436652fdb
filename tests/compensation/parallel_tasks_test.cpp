// details::run_parallel runs every task once on the threads asked, and rethrows a task's
// exception once the running ones have ended, starting no more; SharedProgress reports the tasks'
// mean fraction.
#include "details/parallel_tasks.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace hd = hystbench::compensation::details;

TEST(RunParallel, RunsEveryTaskOnce) {
  std::vector<std::atomic<int>> runs(37);
  hd::run_parallel(runs.size(), [&](std::size_t i) { ++runs[i]; });
  for (const auto& r : runs) EXPECT_EQ(r.load(), 1);
  hd::run_parallel(0, [](std::size_t) { FAIL() << "a task of none ran"; });
}

// On one thread the tasks after the one that threw never start; on several, the ones already
// started end before the exception is rethrown.
TEST(RunParallel, RethrowsATasksExceptionOnceTheRunningOnesHaveEndedAndStartsNoMore) {
  std::atomic<int> started{0};
  std::atomic<int> ended{0};
  const auto task = [&](std::size_t i) {
    ++started;
    if (i == 3) {
      ++ended;
      throw std::invalid_argument("task 3");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ++ended;
  };
  EXPECT_THROW(hd::run_parallel(8, task, 1), std::invalid_argument);
  EXPECT_EQ(started.load(), 4);
  EXPECT_EQ(ended.load(), 4);
  started = 0;
  ended = 0;
  EXPECT_THROW(hd::run_parallel(64, task, 2), std::invalid_argument);
  EXPECT_EQ(ended.load(), started.load());
  EXPECT_LT(started.load(), 64);
}

TEST(RunParallel, RunsOnNoMoreThreadsThanAsked) {
  std::mutex mutex;
  std::set<std::thread::id> seen;
  hd::run_parallel(
      16,
      [&](std::size_t) {
        const std::lock_guard lock(mutex);
        seen.insert(std::this_thread::get_id());
      },
      1);
  ASSERT_EQ(seen.size(), 1U);
  EXPECT_EQ(*seen.begin(), std::this_thread::get_id());
}

TEST(SharedProgress, ReportsTheMeanOfTheTasksFractions) {
  std::vector<double> seen;
  hd::SharedProgress p(4, [&](double f, const std::string&) { seen.push_back(f); });
  p(0, 1.0, "a");
  p(2, 0.5, "b");
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_DOUBLE_EQ(seen[0], 0.25);
  EXPECT_DOUBLE_EQ(seen[1], 0.375);
  hd::SharedProgress quiet(2, {});
  quiet(1, 1.0, "nothing to report to");  // no callback: nothing happens
}
