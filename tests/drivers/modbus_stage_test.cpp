// The Modbus DAQ driver serving a stage of several axes, one register block per axis, against
// hystbench-simdaq --stage xy (the simulated XY stage behind real Modbus TCP on 127.0.0.1).
#include <gtest/gtest.h>

#include <chrono>
#include <iostream>
#include <thread>

#include "hystbench/drivers/driver.hpp"
#include "hystbench/drivers/io_thread_driver.hpp"
#include "hystbench/drivers/modbus_daq.hpp"
#include "hystbench/drivers/simdaq_register_map.hpp"
#include "peer_process.hpp"

namespace hd = hystbench::drivers;
namespace ht = hystbench::test;
using nlohmann::json;
using namespace std::chrono_literals;

namespace {

class ModbusStage : public ::testing::Test {
 protected:
  void SetUp() override {
    simdaq_ = std::make_unique<ht::PeerProcess>(
        std::vector<std::string>{ht::bin("hystbench-simdaq"), "--port", "0", "--stage", "xy"});
    const auto line = simdaq_->wait_for("listening on tcp", 10s);
    ASSERT_TRUE(line) << "hystbench-simdaq did not start";
    port_ = std::stoi(line->substr(line->rfind(':') + 1));
  }
  /// The simdaq map's millivolt output and nanometre position of each axis's block.
  json params(const json& axes, const std::string& io) const {
    return {{"port", port_},
            {"io", io},
            {"axes", axes},
            {"axis_stride", hd::simdaq::kAxisBlock},
            {"max_stale_reads", 2000},
            {"response_timeout_ms", 250},
            {"output", {{"address", hd::simdaq::kHrOutputMv}, {"format", "s32"}, {"scale", 0.001}}},
            {"measurement",
             {{"table", "input"},
              {"address", hd::simdaq::kIrPositionNm},
              {"format", "s32"},
              {"scale", 0.001}}}};
  }
  /// Holds `outputs` for 300 ticks of 1 ms; the last fresh measurement of each axis.
  static std::array<double, 2> hold(hd::Driver& d, const std::array<double, 2>& outputs) {
    std::array<hd::Measurement, 2> m{};
    std::array<double, 2> fresh{NAN, NAN};
    for (int k = 0; k < 300; ++k) {
      EXPECT_EQ(d.write_axes(outputs), hd::DriverStatus::kOk);
      const auto s = d.read_axes(m);
      EXPECT_TRUE(s == hd::DriverStatus::kOk || s == hd::DriverStatus::kStale) << to_string(s);
      if (s == hd::DriverStatus::kOk) fresh = {m[0].position_um, m[1].position_um};
      std::this_thread::sleep_for(1ms);
    }
    return fresh;
  }
  std::unique_ptr<ht::PeerProcess> simdaq_;
  int port_ = 0;
};

}  // namespace

// Each axis's block drives its own axis, on the I/O thread and in the loop: 100 V on x lifts x
// by tens of micrometres and y by the stage's coupling only; 100 V on y the other way round.
// In the loop each tick waits for both exchanges, and activation refuses a 1 kHz loop when
// they take longer than a tick on this machine; that refusal, named as such, skips the loop
// half after three tries, and any other failure fails the test.
TEST_F(ModbusStage, EachAxisBlockDrivesItsOwnAxis) {
  std::string loop_refused;
  for (const std::string io : {"thread", "loop"}) {
    SCOPED_TRACE(io);
    hd::Driver d(hd::make_interface<hd::ModbusDaqDriver, hd::IoThreadDriver>());
    ASSERT_TRUE(d.configure(params({"x", "y"}, io), 1000.0).ok);
    hd::Result r = d.activate();
    for (int attempt = 1; io == "loop" && !r.ok && attempt < 3; ++attempt) r = d.activate();
    if (io == "loop" && !r.ok && r.message.rfind("loop.rate_hz: ", 0) == 0) {
      loop_refused = r.message;
      continue;
    }
    ASSERT_TRUE(r.ok) << r.message;
    const auto rest = hold(d, {0.0, 0.0});
    const auto x_driven = hold(d, {100.0, 0.0});
    const auto y_driven = hold(d, {0.0, 100.0});
    const double x_stroke = x_driven[0] - rest[0], y_stroke = y_driven[1] - rest[1];
    EXPECT_GT(x_stroke, 15.0);
    EXPECT_GT(y_stroke, 15.0);
    // The coupling of the xy stage (x reaches y at 0.1, y reaches x at 0.056), not a copy.
    const double y_from_x = (x_driven[1] - rest[1]) / x_stroke;
    const double x_from_y = (y_driven[0] - rest[0]) / y_stroke;
    EXPECT_GT(y_from_x, 0.07);
    EXPECT_LT(y_from_x, 0.13);
    EXPECT_GT(x_from_y, 0.035);
    EXPECT_LT(x_from_y, 0.08);
    std::cout << "[ modbus stage ] io=" << io << " x stroke " << x_stroke << " um, y stroke "
              << y_stroke << " um, y from x " << y_from_x << ", x from y " << x_from_y << "\n";
    const json diag = d.diagnostics();
    EXPECT_EQ(diag["axes"], 2);
    EXPECT_EQ(diag["axis_names"], json({"x", "y"}));
    EXPECT_EQ(diag["failed_transactions"], 0) << diag.dump();
    EXPECT_TRUE(d.deactivate().ok);
  }
  if (!loop_refused.empty()) GTEST_SKIP() << "the loop half not run: " << loop_refused;
}

// An axis whose block the device does not have is refused at activation, naming the axis and
// the registers.
TEST_F(ModbusStage, ActivationNamesTheAxisWhoseRegistersTheDeviceLacks) {
  hd::Driver d(hd::make_interface<hd::ModbusDaqDriver, hd::IoThreadDriver>());
  ASSERT_TRUE(d.configure(params({"x", "y", "z"}, "thread"), 1000.0).ok);
  const hd::Result r = d.activate();
  ASSERT_FALSE(r.ok);
  EXPECT_NE(r.message.find("holding registers 33-34 of axis z"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("Illegal data address"), std::string::npos) << r.message;
}
