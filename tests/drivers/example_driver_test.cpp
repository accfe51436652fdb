// The example driver of docs/drivers.md (example_driver.hpp, shown there verbatim) through the
// framework: what a driver gets without writing it (lifecycle order, stale accounting, the stale
// limit, on_error() on a fault, the cause in words), and in the real bench loop.
#include "example_driver.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/drivers/driver.hpp"

namespace hd = hystbench::drivers;
namespace hdm = hystbench::daemon;
using nlohmann::json;
using namespace std::chrono_literals;

namespace {
std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
}  // namespace

TEST(ExampleDriver, DocsShowTheFileTheTestBuilds) {
  const std::string src = std::string(HYSTBENCH_SOURCE_DIR) + "/tests/drivers/example_driver.hpp";
  const std::string code = read_file(src);
  ASSERT_FALSE(code.empty()) << src;
  const std::string docs = read_file(std::string(HYSTBENCH_SOURCE_DIR) + "/docs/drivers.md");
  EXPECT_NE(docs.find("```cpp\n" + code + "```\n"), std::string::npos)
      << "docs/drivers.md must show tests/drivers/example_driver.hpp verbatim";
}

TEST(ExampleDriver, TheFrameworkRefusesCallsOutOfOrderAndRatesTheDriverCannotHold) {
  hd::Driver d(std::make_unique<example::FirstOrderDriver>());
  hd::Measurement m;
  EXPECT_EQ(d.write(1.0), hd::DriverStatus::kFault);
  EXPECT_EQ(d.read(m), hd::DriverStatus::kFault);
  EXPECT_EQ(d.activate().message, "driver.first_order: activate() before configure()");
  EXPECT_EQ(d.configure({{"gain", 1}}, 1000.0).message, "driver.first_order.gain: unknown key");
  EXPECT_EQ(d.configure(json::object(), 20000.0).message,
            "loop.rate_hz: 20000 Hz is beyond what the first_order driver holds as configured "
            "(at most 10000 Hz)");
  EXPECT_EQ(d.configure(json::object(), 0.0).message, "loop.rate_hz: must be > 0");
  EXPECT_EQ(d.state(), hd::Driver::State::kUnconfigured);
  ASSERT_TRUE(d.configure(json::object(), 1000.0).ok);
  EXPECT_EQ(d.state(), hd::Driver::State::kInactive);
  EXPECT_EQ(d.write(1.0), hd::DriverStatus::kFault);
  ASSERT_TRUE(d.activate().ok);
  EXPECT_EQ(d.configure(json::object(), 1000.0).message,
            "driver.first_order: configure() while active");
  EXPECT_TRUE(d.deactivate().ok);
  EXPECT_EQ(d.state(), hd::Driver::State::kInactive);
}

TEST(ExampleDriver, StaleReadsRepeatTheLastValueWithItsAge) {
  hd::Driver d(std::make_unique<example::FirstOrderDriver>());
  ASSERT_TRUE(d.configure({{"gain_um_per_v", 0.1}}, 1000.0).ok);
  ASSERT_TRUE(d.activate().ok);
  hd::Measurement m;
  ASSERT_EQ(d.write(100.0), hd::DriverStatus::kOk);
  ASSERT_EQ(d.read(m), hd::DriverStatus::kStale);  // tick 1: nothing new, the activation value
  EXPECT_EQ(m.position_um, 0.0);
  EXPECT_EQ(m.age_ticks, 1u);
  ASSERT_EQ(d.read(m), hd::DriverStatus::kOk);
  EXPECT_GT(m.position_um, 0.0);
  EXPECT_EQ(m.age_ticks, 0u);
  const double fresh = m.position_um;
  ASSERT_EQ(d.read(m), hd::DriverStatus::kStale);
  EXPECT_EQ(m.position_um, fresh);
  EXPECT_EQ(m.age_ticks, 1u);
  EXPECT_EQ(d.diagnostics()["stale_reads"], 2);
  EXPECT_EQ(d.diagnostics()["position_um"], fresh);
  EXPECT_EQ(d.diagnostics()["output_v"], 100.0);
  EXPECT_EQ(d.diagnostics()["last_fault"], "none");
}

TEST(ExampleDriver, AFaultCallsOnErrorOnceAndIsNamedInWords) {
  hd::Driver d(std::make_unique<example::FirstOrderDriver>());
  ASSERT_TRUE(d.configure(json::object(), 1000.0).ok);
  ASSERT_TRUE(d.activate().ok);
  hd::Measurement m;
  hd::DriverStatus s = hd::DriverStatus::kOk;
  for (int k = 0; k < 1000 && s != hd::DriverStatus::kFault; ++k) {
    d.write(150.0);  // 30 um at 0.2 um/V: beyond the 25 um travel
    s = d.read(m);
  }
  ASSERT_EQ(s, hd::DriverStatus::kFault);
  const json diag = d.diagnostics();
  EXPECT_EQ(diag["last_fault"], "over travel: 25 um (at most 25 um)") << diag.dump();
  EXPECT_EQ(diag["output_v"], 0.0);  // on_error() drove the safe output in that read
  // The safe output lets the actuator relax: the next fresh value ends the fault.
  for (int k = 0; k < 10 && s != hd::DriverStatus::kOk; ++k) s = d.read(m);
  EXPECT_EQ(s, hd::DriverStatus::kOk);
  EXPECT_LT(m.position_um, 25.0);
}

TEST(ExampleDriver, RunsInTheBenchLoop) {
  hd::Driver d(std::make_unique<example::FirstOrderDriver>());
  ASSERT_TRUE(d.configure({{"gain_um_per_v", 0.1}}, 2000.0).ok);
  ASSERT_TRUE(d.activate().ok);
  hdm::BenchLoopOptions o;
  o.rate_hz = 2000.0;
  o.realtime.fifo = false;
  o.realtime.lock_memory = false;
  o.overrun_budget = 1000000;
  hdm::BenchLoop loop(d, o);
  loop.start();
  auto p = std::make_unique<hdm::RunProgram>();
  p->kind = hdm::RunKind::kIdentify;
  p->excitation.assign(2000, 100.0);
  p->total_samples = 2000;
  p->records.capacity = 2000;
  p->records.u.resize(2000);
  p->records.y.resize(2000);
  p->records.yr.resize(2000);
  ASSERT_EQ(loop.submit(std::move(p)), nullptr);
  std::unique_ptr<hdm::RunProgram> done;
  for (int i = 0; i < 5000 && !done; ++i) {
    done = loop.take_finished();
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_NE(done, nullptr);
  EXPECT_EQ(done->end, hdm::RunEnd::kCompleted);
  EXPECT_GE(done->counters.stale_reads, 990u);  // every second tick
  ASSERT_EQ(done->records.count, 2000u);
  EXPECT_GT(done->records.u.back(), 50.0);
  EXPECT_NEAR(done->records.y.back(), 0.1 * done->records.u.back(), 0.5);  // 0.1 um/V
  loop.shutdown();
  EXPECT_TRUE(d.deactivate().ok);
}
