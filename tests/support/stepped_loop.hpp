#pragma once
// A BenchLoop stepped by hand on the test's thread (BenchLoop::step()) behind a driver made of
// `stage`, its clock a fake that advances 1 µs per reading: the per-tick path runs the same way
// every time. It has taken one idle tick (the loop takes runs once it runs).
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>

#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/drivers/driver.hpp"

namespace hystbench::test {

struct SteppedLoop {
  std::unique_ptr<drivers::Driver> driver;
  std::unique_ptr<daemon::BenchLoop> loop;
};

inline std::int64_t stepped_loop_clock() noexcept {
  static std::int64_t now = 0;
  return now += 1000;
}

inline SteppedLoop stepped_loop(std::unique_ptr<drivers::DriverInterface> stage, double rate_hz) {
  SteppedLoop s;
  s.driver = std::make_unique<drivers::Driver>(std::move(stage));
  EXPECT_TRUE(s.driver->configure(nlohmann::json::object(), rate_hz).ok);
  EXPECT_TRUE(s.driver->activate().ok);
  daemon::BenchLoopOptions o;
  o.rate_hz = rate_hz;
  o.clock_ns = &stepped_loop_clock;
  s.loop = std::make_unique<daemon::BenchLoop>(*s.driver, o);
  s.loop->step();
  return s;
}

}  // namespace hystbench::test
