// details::run_parallel runs every task once and rethrows a task's exception after all have
// ended; SharedProgress reports the tasks' mean fraction.
#include "details/parallel_tasks.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

namespace hd = hystbench::compensation::details;

TEST(RunParallel, RunsEveryTaskOnce) {
  std::vector<std::atomic<int>> runs(37);
  hd::run_parallel(runs.size(), [&](std::size_t i) { ++runs[i]; });
  for (const auto& r : runs) EXPECT_EQ(r.load(), 1);
  hd::run_parallel(0, [](std::size_t) { FAIL() << "a task of none ran"; });
}

TEST(RunParallel, RethrowsATasksExceptionAfterEveryTaskHasEnded) {
  std::atomic<int> ended{0};
  EXPECT_THROW(hd::run_parallel(8,
                                [&](std::size_t i) {
                                  ++ended;
                                  if (i == 3) throw std::invalid_argument("task 3");
                                }),
               std::invalid_argument);
  EXPECT_EQ(ended.load(), 8);
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
