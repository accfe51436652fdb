// A stage of several axes through the loopback driver and the driver framework: every axis in
// one tick, the first alone through write()/read(), faults and stale ticks per axis, and the
// refusals that name the cause.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "hystbench/drivers/driver.hpp"
#include "hystbench/drivers/io_thread_driver.hpp"
#include "hystbench/drivers/loopback_driver.hpp"
#include "hystbench/sim/simulated_stage.hpp"

namespace hd = hystbench::drivers;
namespace hs = hystbench::sim;
using nlohmann::json;

namespace {

constexpr double kRate = 10000.0;

std::unique_ptr<hd::Driver> active_stage(const json& stage = json::object()) {
  auto driver = hd::make_driver("loopback");
  const hd::Result configured = driver->configure({{"stage", stage}}, kRate);
  EXPECT_TRUE(configured.ok) << configured.message;
  const hd::Result activated = driver->activate();
  EXPECT_TRUE(activated.ok) << activated.message;
  return driver;
}

std::array<double, 2> drive(int k) {
  return {75.0 + 60.0 * std::sin(2.0 * M_PI * 7.0 * k / kRate),
          70.0 + 50.0 * std::sin(2.0 * M_PI * 3.0 * k / kRate)};
}

}  // namespace

TEST(LoopbackStage, EveryAxisInOneTickIsTheSimulatedStageSampleForSample) {
  auto driver = active_stage();
  ASSERT_EQ(driver->axes(), 2u);
  hs::SimulatedStage truth(hs::SimulatedStageConfig::xy(), 1.0 / kRate);
  const double safe[2] = {0.0, 0.0};
  truth.reset(safe);
  std::array<hd::Measurement, 2> m{};
  double y[2];
  for (int k = 0; k < 3000; ++k) {
    const auto u = drive(k);
    ASSERT_EQ(driver->write_axes(u), hd::DriverStatus::kOk);
    ASSERT_EQ(driver->read_axes(m), hd::DriverStatus::kOk);
    truth.step(u, y);
    ASSERT_EQ(m[0].position_um, y[0]) << "tick " << k;
    ASSERT_EQ(m[1].position_um, y[1]) << "tick " << k;
  }
  EXPECT_EQ(driver->diagnostics()["axes"], 2);
}

TEST(LoopbackStage, WriteAndReadServeTheFirstAxisWhileTheOthersHoldTheSafeOutput) {
  auto driver = active_stage();
  hs::SimulatedStage truth(hs::SimulatedStageConfig::xy(), 1.0 / kRate);
  const double safe[2] = {0.0, 0.0};
  truth.reset(safe);
  double y[2];
  hd::Measurement m;
  for (int k = 0; k < 2000; ++k) {
    const double u[2] = {drive(k)[0], 0.0};
    ASSERT_EQ(driver->write(u[0]), hd::DriverStatus::kOk);
    ASSERT_EQ(driver->read(m), hd::DriverStatus::kOk);
    truth.step(u, y);
    ASSERT_EQ(m.position_um, y[0]) << "tick " << k;
  }
  // What x's motion left on the held y: the coupling is there.
  const hs::SimulatedStage at_rest(hs::SimulatedStageConfig::xy(), 1.0 / kRate);
  EXPECT_GT(std::abs(truth.axis(1).true_position() - at_rest.axis(1).true_position()), 0.5);
}

TEST(LoopbackStage, AFailedReadKeepsEachAxisLastValueWithItsAge) {
  auto driver = active_stage();
  auto* loopback = dynamic_cast<hd::LoopbackDriver*>(&driver->interface());
  ASSERT_NE(loopback, nullptr);
  std::array<hd::Measurement, 2> m{};
  for (int k = 0; k < 500; ++k) {
    driver->write_axes(drive(k));
    driver->read_axes(m);
  }
  const std::array<hd::Measurement, 2> last = m;
  ASSERT_GT(std::abs(last[0].position_um - last[1].position_um), 1.0);
  loopback->inject({.read_error_at_tick = 1});
  for (std::uint64_t age = 1; age <= 3; ++age) {
    driver->write_axes(drive(0));
    EXPECT_EQ(driver->read_axes(m), hd::DriverStatus::kError);
    for (std::size_t i = 0; i < 2; ++i) {
      EXPECT_EQ(m[i].position_um, last[i].position_um) << "axis " << i;
      EXPECT_EQ(m[i].age_ticks, age) << "axis " << i;
    }
  }
}

TEST(LoopbackStage, TheFrameworkNamesAConfigurationOfMoreAxesThanTheDriverServes) {
  auto one = hd::make_driver("loopback");
  ASSERT_TRUE(one->configure(json::object(), kRate).ok);
  EXPECT_EQ(one->axes(), 1u);
  EXPECT_TRUE(one->serves(1).ok);
  EXPECT_EQ(one->serves(2).message,
            "axes: the loopback driver serves 1 axis, the configuration names 2 axes");
  auto two = active_stage();
  EXPECT_TRUE(two->serves(2).ok);
  EXPECT_EQ(two->serves(3).message,
            "axes: the loopback driver serves 2 axes, the configuration names 3 axes");
  EXPECT_FALSE(two->serves(0).ok);
}

TEST(LoopbackStage, BadStageConfigurationsAreRefusedNamingTheKey) {
  auto driver = hd::make_driver("loopback");
  hd::Result r =
      driver->configure({{"actuator", json::object()}, {"stage", json::object()}}, kRate);
  EXPECT_NE(r.message.find("give \"actuator\" or \"stage\", not both"), std::string::npos)
      << r.message;
  r = driver->configure({{"stage", {{"coupling", {{"gains", {{0.2, 0.1}, {0.1, 0.0}}}}}}}}, kRate);
  EXPECT_EQ(r.message,
            "driver.loopback.stage.coupling.gains[0][0]: must be 0 (an axis's own gain is its "
            "actuator's)");
  r = driver->configure(json::parse(R"({"stage": {"axes": [{"name": "x"},
      {"name": "y", "actuator": {"input": {"max_v": 100}}}]}})"),
                        kRate);
  EXPECT_EQ(r.message,
            "driver.loopback.stage.axes[1].actuator.input: the loopback's axes share one input "
            "range, axis 0's");
  EXPECT_EQ(driver->state(), hd::Driver::State::kUnconfigured);
}

namespace {

// A driver of two axes whose exchanges block: it asks for the I/O thread, and echoes each
// axis's output as its position, doubled.
class TwoAxesOnAThread final : public hd::DriverInterface {
 public:
  hd::Result on_configure(const json&, double) override { return hd::Result::success(); }
  hd::Result on_activate() override { return hd::Result::success(); }
  hd::DriverStatus write(double u) noexcept override { return write_axes({&u, 1}); }
  hd::DriverStatus read(hd::Measurement& m) noexcept override { return read_axes({&m, 1}); }
  hd::DriverStatus write_axes(std::span<const double> u) noexcept override {
    for (std::size_t a = 0; a < u.size() && a < 2; ++a) u_[a] = u[a];
    return hd::DriverStatus::kOk;
  }
  hd::DriverStatus read_axes(std::span<hd::Measurement> m) noexcept override {
    for (std::size_t a = 0; a < m.size() && a < 2; ++a) m[a].position_um = 2.0 * u_[a];
    return hd::DriverStatus::kOk;
  }
  hd::DriverStatus safe_state() noexcept override { return write_axes(std::array{0.0, 0.0}); }
  std::size_t axes() const noexcept override { return 2; }
  hd::DriverInfo info() const noexcept override {
    hd::DriverInfo i;
    i.max_rate_hz = 1000.0;
    i.output_max_v = 10.0;
    i.io_thread = true;
    return i;
  }
  std::string_view type() const noexcept override { return "two_axes"; }

 private:
  std::array<double, 2> u_{};
};

/// Ticks write_axes(u) then read_axes() until a fresh reading comes (at most 2 s).
std::array<double, 2> fresh_reading(hd::Driver& d, std::span<const double> u) {
  std::array<hd::Measurement, 2> m{};
  for (int k = 0; k < 2000; ++k) {
    if (u.size() == 1) {
      d.write(u[0]);
    } else {
      d.write_axes(u);
    }
    if (d.read_axes(m) == hd::DriverStatus::kOk) return {m[0].position_um, m[1].position_um};
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ADD_FAILURE() << "no fresh reading in 2 s";
  return {NAN, NAN};
}

}  // namespace

// The I/O thread exchanges every axis of the driver it wraps: write_axes() sets every axis's
// command, write() the first one's while the others hold theirs.
TEST(LoopbackStage, TheIoThreadExchangesEveryAxisOfTheDriverItWraps) {
  hd::Driver driver(std::make_unique<hd::IoThreadDriver>(std::make_unique<TwoAxesOnAThread>()));
  ASSERT_TRUE(driver.configure(json::object(), 1000.0).ok);
  ASSERT_TRUE(driver.activate().ok);
  ASSERT_EQ(driver.axes(), 2u);
  EXPECT_EQ(fresh_reading(driver, std::array{1.0, 3.0}), (std::array{2.0, 6.0}));
  // A fresh reading may answer the command before; the one after it answers this one.
  fresh_reading(driver, std::array{5.0});
  EXPECT_EQ(fresh_reading(driver, std::array{5.0}), (std::array{10.0, 6.0}));
  EXPECT_EQ(driver.safe_state(), hd::DriverStatus::kOk);
  EXPECT_TRUE(driver.deactivate().ok);
}
