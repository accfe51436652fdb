// GPIO lines on a driver, through lines the test owns (MemoryGpioBackend; this machine has no
// GPIO chip), with the real bench loop: enable and run-active follow the run, sync pulses, the
// e-stop makes the output safe within a tick and faults the run. The libgpiod backend is
// exercised where /dev/gpiochip* exists, and for its error messages everywhere.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/drivers/gpio_driver.hpp"
#include "hystbench/drivers/loopback_driver.hpp"

namespace hd = hystbench::drivers;
namespace hdm = hystbench::daemon;
using nlohmann::json;
using namespace std::chrono_literals;

namespace {

const json kGpio = {{"chip", "sim0"},
                    {"enable", {{"line", "AMP_EN"}}},
                    {"estop", {{"line", 4}}},  // active low by default
                    {"run_active", {{"line", "RUN"}}},
                    {"sync_pulse", {{"line", "SYNC"}}},
                    {"sync_every_ticks", 500}};

class GpioLoopTest : public ::testing::Test {
 protected:
  void SetUp() override {
    gpio_ = std::make_shared<hd::MemoryGpioBackend>();
    gpio_->set_level("sim0:4", true);  // e-stop released (pulled up)
    driver_ = std::make_unique<hd::Driver>(
        std::make_unique<hd::GpioDriver>(std::make_unique<hd::LoopbackDriver>(), gpio_));
    ASSERT_TRUE(driver_->configure({{"gpio", kGpio}}, 2000.0).ok);
    const auto r = driver_->activate();
    ASSERT_TRUE(r.ok) << r.message;
    hdm::BenchLoopOptions o;
    o.rate_hz = 2000.0;
    o.realtime.fifo = false;
    o.realtime.lock_memory = false;
    o.overrun_budget = 1000000;
    loop_ = std::make_unique<hdm::BenchLoop>(*driver_, o);
    loop_->start();
  }
  void TearDown() override {
    loop_.reset();
    driver_->deactivate();
    EXPECT_EQ(gpio_->requested(), 0);
  }
  /// A run of `n` samples at 100 V.
  static std::unique_ptr<hdm::RunProgram> program(std::size_t n) {
    auto p = std::make_unique<hdm::RunProgram>();
    p->kind = hdm::RunKind::kIdentify;
    p->excitation.assign(n, 100.0);
    p->total_samples = n;
    return p;
  }
  std::unique_ptr<hdm::RunProgram> wait_finished(std::chrono::milliseconds timeout) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < until) {
      if (auto p = loop_->take_finished()) return p;
      std::this_thread::sleep_for(1ms);
    }
    return nullptr;
  }
  bool wait_running() {
    for (int i = 0; i < 2000 && loop_->state() != hdm::BenchLoop::State::kRunning; ++i) {
      std::this_thread::sleep_for(1ms);
    }
    return loop_->state() == hdm::BenchLoop::State::kRunning;
  }

  std::shared_ptr<hd::MemoryGpioBackend> gpio_;
  std::unique_ptr<hd::Driver> driver_;
  std::unique_ptr<hdm::BenchLoop> loop_;
};

}  // namespace

TEST_F(GpioLoopTest, EnableAndRunActiveFollowTheRunAndSyncPulses) {
  std::this_thread::sleep_for(20ms);
  EXPECT_FALSE(gpio_->level("sim0:AMP_EN"));  // idle: amplifier disabled
  EXPECT_FALSE(gpio_->level("sim0:RUN"));
  ASSERT_EQ(loop_->submit(program(2000)), nullptr);  // 1 s
  ASSERT_TRUE(wait_running());
  EXPECT_TRUE(gpio_->level("sim0:AMP_EN"));
  EXPECT_TRUE(gpio_->level("sim0:RUN"));
  auto done = wait_finished(5s);
  ASSERT_NE(done, nullptr);
  EXPECT_EQ(done->end, hdm::RunEnd::kCompleted);
  EXPECT_FALSE(gpio_->level("sim0:AMP_EN"));
  EXPECT_FALSE(gpio_->level("sim0:RUN"));
  EXPECT_FALSE(gpio_->level("sim0:SYNC"));
  // One pulse at the start, then every 500 ticks: 0, 500, 1000, 1500.
  EXPECT_EQ(gpio_->rising_edges("sim0:SYNC"), 4);
  EXPECT_EQ(gpio_->rising_edges("sim0:AMP_EN"), 1);
}

TEST_F(GpioLoopTest, EstopMidRunIsSafeWithinOneTickAndFaultsUntilReleasedAndReset) {
  ASSERT_EQ(loop_->submit(program(20000)), nullptr);
  ASSERT_TRUE(wait_running());
  std::this_thread::sleep_for(100ms);
  const std::uint64_t before = loop_->active()->done.load();
  gpio_->set_level("sim0:4", false);  // pressed
  auto done = wait_finished(2s);
  ASSERT_NE(done, nullptr);
  EXPECT_EQ(done->end, hdm::RunEnd::kFault);
  EXPECT_STREQ(done->end_reason, "driver write failed");
  // The tick in progress at most, then the next one sees the e-stop.
  EXPECT_LE(done->done.load(), before + 2);
  EXPECT_EQ(loop_->state(), hdm::BenchLoop::State::kFault);
  EXPECT_FALSE(gpio_->level("sim0:AMP_EN"));
  EXPECT_FALSE(gpio_->level("sim0:RUN"));
  EXPECT_EQ(loop_->last_output(), driver_->safe_output_v());
  // The loopback itself holds the safe output, not only the framework's record of it.
  auto& gpio_driver = static_cast<hd::GpioDriver&>(driver_->interface());
  EXPECT_EQ(gpio_driver.inner().diagnostics()["output_v"], driver_->safe_output_v());
  const json d = driver_->diagnostics();
  EXPECT_TRUE(d["gpio"]["estop_asserted"].get<bool>());
  EXPECT_EQ(d["last_fault"], "e-stop asserted (sim0:4)");
  // Held: a reset faults again at once. Released: the loop resets and runs again.
  loop_->reset_fault();
  std::this_thread::sleep_for(20ms);
  EXPECT_EQ(loop_->state(), hdm::BenchLoop::State::kFault);
  gpio_->set_level("sim0:4", true);
  EXPECT_TRUE(loop_->reset_fault());
  ASSERT_EQ(loop_->submit(program(200)), nullptr);
  done = wait_finished(5s);
  ASSERT_NE(done, nullptr);
  EXPECT_EQ(done->end, hdm::RunEnd::kCompleted);
  EXPECT_EQ(driver_->diagnostics()["gpio"]["estop_trips"], 1);
}

TEST(GpioDriver, RefusesToActivateWithTheEstopAssertedAndReleasesItsLines) {
  auto gpio = std::make_shared<hd::MemoryGpioBackend>();
  hd::Driver d(std::make_unique<hd::GpioDriver>(std::make_unique<hd::LoopbackDriver>(), gpio));
  ASSERT_TRUE(d.configure({{"gpio", kGpio}}, 1000.0).ok);
  gpio->set_level("sim0:4", false);
  const auto r = d.activate();
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.message, "driver.loopback.gpio: the e-stop is asserted (sim0:4); release it first");
  EXPECT_EQ(gpio->requested(), 0);
}

TEST(GpioDriver, WithoutAGpioTableItOnlyForwards) {
  auto gpio = std::make_shared<hd::MemoryGpioBackend>();
  hd::Driver d(std::make_unique<hd::GpioDriver>(std::make_unique<hd::LoopbackDriver>(), gpio));
  ASSERT_TRUE(d.configure(json::object(), 1000.0).ok);
  ASSERT_TRUE(d.activate().ok);
  EXPECT_EQ(d.type(), "loopback");
  // The simulated 16-bit ADC over -10..60 um, as the stuck-sensor rule needs it.
  EXPECT_DOUBLE_EQ(d.measurement_resolution_um(), 70.0 / 65535.0);
  EXPECT_FALSE(d.diagnostics().contains("gpio"));
  EXPECT_EQ(gpio->requested(), 0);
  hd::Measurement m;
  EXPECT_EQ(d.write(10.0), hd::DriverStatus::kOk);
  EXPECT_EQ(d.read(m), hd::DriverStatus::kOk);
}

TEST(GpioConfig, ErrorsNameTheKey) {
  hd::Driver d(std::make_unique<hd::GpioDriver>(std::make_unique<hd::LoopbackDriver>(),
                                                std::make_shared<hd::MemoryGpioBackend>()));
  EXPECT_EQ(d.configure({{"gpio", {{"enable", {{"active_low", true}}}}}}, 1000.0).message,
            "driver.loopback.gpio.enable.line: required (name or offset)");
  EXPECT_EQ(d.configure({{"gpio", {{"estop", {{"line", -3}}}}}}, 1000.0).message,
            "driver.loopback.gpio.estop.line: must be a line name or a non-negative offset");
  EXPECT_EQ(d.configure({{"gpio", {{"e_stop", {{"line", 3}}}}}}, 1000.0)
                .message.rfind("driver.loopback.gpio.e_stop: unknown key", 0),
            0u);
  const auto c = hd::parse_gpio_config({{"chip", "gpiochip2"},
                                        {"estop", {{"line", 7}}},
                                        {"enable", {{"line", "EN"}, {"chip", "1"}}}},
                                       "g");
  EXPECT_EQ(c.estop->describe(), "gpiochip2:7");
  EXPECT_TRUE(c.estop->active_low);
  ASSERT_EQ(c.enable.size(), 1u);
  EXPECT_EQ(c.enable[0].describe(), "1:EN");
  EXPECT_FALSE(c.enable[0].active_low);
}

TEST(GpioLibgpiod, NamesTheMissingChipOrLine) {
  auto backend = hd::make_libgpiod_backend();
  try {
    backend->request_output({"hystbench-no-such-chip", "AMP_EN", false}, false, "test");
    FAIL() << "a missing chip was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no GPIO chip 'hystbench-no-such-chip'"),
              std::string::npos)
        << e.what();
  }
  bool have_chip = false;
  for (const auto& e : std::filesystem::directory_iterator("/dev")) {
    have_chip = have_chip || e.path().filename().string().rfind("gpiochip", 0) == 0;
  }
  if (!have_chip) GTEST_SKIP() << "no /dev/gpiochip* on this machine: libgpiod lines not tried";
  try {
    backend->request_input({"gpiochip0", "hystbench-no-such-line", false}, "test");
    FAIL() << "a missing line was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no line named hystbench-no-such-line"), std::string::npos)
        << e.what();
  }
}

TEST(GpioDriver, TheEstopGuardsEveryAxisOfAStage) {
  auto gpio = std::make_shared<hd::MemoryGpioBackend>();
  gpio->set_level("sim0:4", true);
  hd::Driver d(std::make_unique<hd::GpioDriver>(std::make_unique<hd::LoopbackDriver>(), gpio));
  ASSERT_TRUE(d.configure({{"gpio", kGpio}, {"stage", json::object()}}, 1000.0).ok);
  ASSERT_TRUE(d.activate().ok);
  ASSERT_EQ(d.axes(), 2u);
  const double u[2] = {50.0, 60.0};
  hd::Measurement m[2];
  EXPECT_EQ(d.write_axes(u), hd::DriverStatus::kOk);
  EXPECT_EQ(d.read_axes(m), hd::DriverStatus::kOk);
  gpio->set_level("sim0:4", false);  // asserted
  EXPECT_EQ(d.write_axes(u), hd::DriverStatus::kFault);
  EXPECT_EQ(d.read_axes(m), hd::DriverStatus::kFault);
  d.deactivate();
}

// A stage's amplifier channels each have their enable line: every one follows the run and goes
// off on the e-stop; a count other than one or the axes is refused, naming the key.
TEST(GpioDriver, AStageHasAnEnableLinePerAxis) {
  auto gpio = std::make_shared<hd::MemoryGpioBackend>();
  gpio->set_level("sim0:4", true);
  json lines = kGpio;
  lines["enable"] = {{{"line", "X_EN"}}, {{"line", "Y_EN"}, {"active_low", true}}};
  hd::Driver d(std::make_unique<hd::GpioDriver>(std::make_unique<hd::LoopbackDriver>(), gpio));
  ASSERT_TRUE(d.configure({{"gpio", lines}, {"stage", json::object()}}, 1000.0).ok);
  ASSERT_TRUE(d.activate().ok);
  EXPECT_FALSE(gpio->level("sim0:X_EN"));
  EXPECT_TRUE(gpio->level("sim0:Y_EN"));  // active low: high is off
  d.set_run_active(true);
  EXPECT_TRUE(gpio->level("sim0:X_EN"));
  EXPECT_FALSE(gpio->level("sim0:Y_EN"));
  EXPECT_EQ(d.diagnostics()["gpio"]["lines"]["enable"],
            json({"sim0:X_EN", "sim0:Y_EN (active low)"}));
  gpio->set_level("sim0:4", false);  // e-stop asserted: every axis's amplifier off
  const double u[2] = {50.0, 60.0};
  EXPECT_EQ(d.write_axes(u), hd::DriverStatus::kFault);
  EXPECT_FALSE(gpio->level("sim0:X_EN"));
  EXPECT_TRUE(gpio->level("sim0:Y_EN"));
  d.deactivate();
  EXPECT_EQ(gpio->requested(), 0);

  lines["enable"] = {{{"line", "X_EN"}}, {{"line", "Y_EN"}}, {{"line", "Z_EN"}}};
  EXPECT_EQ(d.configure({{"gpio", lines}, {"stage", json::object()}}, 1000.0).message,
            "driver.loopback.gpio.enable: 3 lines for a driver of 2 axes: give one line (every "
            "axis) or one per axis");
  lines["enable"] = {{{"line", "X_EN"}}, {{"chip", "sim1"}}};
  EXPECT_EQ(d.configure({{"gpio", lines}, {"stage", json::object()}}, 1000.0).message,
            "driver.loopback.gpio.enable[1].line: required (name or offset)");
}
