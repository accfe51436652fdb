#pragma once
// The bench's parts without a Bench, for a component's own tests (the identify coordinator, the
// run hand-back): the example first-order driver behind a loop that is never started, the
// bench's mutex, and a run supervisor whose thread is never started.
#include <gtest/gtest.h>

#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>

#include "drivers/example_driver.hpp"
#include "hystbench/daemon/config/bench_settings.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"
#include "service/details/bench_parts.hpp"
#include "service/details/run_supervisor.hpp"

namespace hystbench::test {

struct BenchPartsHarness {
  daemon::BenchSettings settings;
  std::unique_ptr<drivers::Driver> driver;
  std::unique_ptr<daemon::BenchLoop> loop;
  std::mutex mutex;
  std::unique_ptr<daemon::details::RunSupervisor> runs;

  /// The loop's rate [Hz].
  explicit BenchPartsHarness(double rate_hz = 2000.0) {
    settings.loop.rate_hz = rate_hz;
    driver = std::make_unique<drivers::Driver>(std::make_unique<example::FirstOrderDriver>());
    EXPECT_TRUE(driver->configure(nlohmann::json::object(), settings.loop.rate_hz).ok);
    EXPECT_TRUE(driver->activate().ok);
    loop = std::make_unique<daemon::BenchLoop>(*driver, settings.loop);
    runs = std::make_unique<daemon::details::RunSupervisor>(*loop, mutex, settings);
  }

  daemon::details::BenchParts parts() { return {settings, *loop, *runs, mutex}; }
};

}  // namespace hystbench::test
