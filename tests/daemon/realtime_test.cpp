#include "hystbench/daemon/realtime.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

#include <cerrno>
#include <iostream>
#include <thread>

namespace hd = hystbench::daemon;

TEST(Realtime, FifoPriorityIsAppliedOrReportedNotPermitted) {
  EXPECT_EQ(hd::set_fifo_priority(0).error, EINVAL);
  EXPECT_EQ(hd::set_fifo_priority(100).error, EINVAL);
  std::thread t([] {
    const auto st = hd::set_fifo_priority(10);
    EXPECT_TRUE(st.ok() || st.not_permitted()) << st.describe();
    if (st.ok()) {
      int policy = 0;
      sched_param param{};
      pthread_getschedparam(pthread_self(), &policy, &param);
      EXPECT_EQ(policy, SCHED_FIFO);
      EXPECT_EQ(param.sched_priority, 10);
      EXPECT_TRUE(hd::set_normal_scheduling().ok());
      pthread_getschedparam(pthread_self(), &policy, &param);
      EXPECT_EQ(policy, SCHED_OTHER);
    } else {
      EXPECT_NE(st.describe().find("sched_setscheduler"), std::string::npos);
    }
  });
  t.join();
}

TEST(Realtime, TimerSlackIsSetForTheCallingThread) {
  EXPECT_EQ(hd::set_timer_slack(0).error, EINVAL);
  std::thread t([] {
    ASSERT_TRUE(hd::set_timer_slack(1).ok());
    EXPECT_EQ(prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0), 1);
  });
  t.join();
}

TEST(Realtime, AffinityPinsTheCallingThread) {
  EXPECT_TRUE(hd::pin_to_cpu(-1).ok());
  EXPECT_EQ(hd::pin_to_cpu(100000).error, EINVAL);
  std::thread t([] {
    ASSERT_TRUE(hd::pin_to_cpu(0).ok());
    EXPECT_EQ(sched_getcpu(), 0);
  });
  t.join();
}

TEST(Realtime, ApplyReportsEachStepAndSaysWhenDegraded) {
  std::thread t([] {
    const hd::RealtimeOptions options{true, 20, 0, true};
    const auto report = hd::apply_realtime(options);
    const std::string line = report.summary(options);
    std::cout << "[ measure  ] " << line << "\n";
    EXPECT_NE(line.find("SCHED_FIFO 20"), std::string::npos);
    EXPECT_EQ(report.degraded(), line.find("running degraded") != std::string::npos);
    EXPECT_TRUE(report.affinity.ok());
    hd::set_normal_scheduling();
    if (report.memory.ok()) {
      EXPECT_TRUE(hd::unlock_memory().ok());
    }
  });
  t.join();
  const auto nothing = hd::apply_realtime({false, 80, -1, false});
  EXPECT_FALSE(nothing.degraded());
}

TEST(Realtime, PrefaultStackTouchesPagesWithoutCrashing) {
  hd::prefault_stack();
  hd::prefault_stack(std::size_t{64} << 20);  // clamped
}
