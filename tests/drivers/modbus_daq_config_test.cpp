// The [driver.modbus] table: defaults, and errors that name the key and the cause.
#include "hystbench/drivers/modbus_daq_config.hpp"

#include <gtest/gtest.h>

#include "hystbench/drivers/driver.hpp"
#include "hystbench/drivers/io_thread_driver.hpp"
#include "hystbench/drivers/modbus_daq.hpp"

namespace hd = hystbench::drivers;
using nlohmann::json;

namespace {
std::string error_of(const json& params) {
  try {
    hd::parse_modbus_daq_config(params);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "ok";
}
}  // namespace

TEST(ModbusDaqConfig, DefaultsAreTcpOnTheIoThread) {
  const auto c = hd::parse_modbus_daq_config(json());
  EXPECT_EQ(c.transport, hd::ModbusDaqConfig::Transport::kTcp);
  EXPECT_EQ(c.io, hd::ModbusDaqConfig::IoMode::kThread);
  EXPECT_EQ(c.endpoint(), "tcp 127.0.0.1:502");
  EXPECT_EQ(c.safe_output_v, 0.0);
}

TEST(ModbusDaqConfig, ErrorsNameTheKeyPath) {
  EXPECT_EQ(error_of({{"bogus", 1}}).rfind("driver.modbus.bogus: unknown key", 0), 0u);
  EXPECT_EQ(error_of({{"output", {{"format", "u64"}}}}),
            "driver.modbus.output.format: unknown 'u64' (u16, s16, u32, s32)");
  EXPECT_EQ(error_of({{"output", {{"table", "input"}}}}),
            "driver.modbus.output.table: unknown 'input' (holding)");
  EXPECT_EQ(error_of({{"port", 70000}}).rfind("driver.modbus.port: must be in [1, 65535]", 0), 0u);
  EXPECT_EQ(error_of({{"device", "/dev/ttyS0"}}),
            "driver.modbus.device: only for transport = \"rtu\"");
  EXPECT_NE(error_of({{"write_read", true}}).find("function 23 reads holding registers"),
            std::string::npos);
  EXPECT_NE(error_of({{"output", {{"max_v", 200}}}}).find("beyond the u16 range"),
            std::string::npos);
  EXPECT_EQ(error_of({{"safe_output_v", 151}}).rfind("driver.modbus.safe_output_v", 0), 0u);
}

TEST(ModbusDaqConfig, RtuRateFollowsTheWireTime) {
  // 115200 8N1, function 23 with one register each way: 15 + 7 bytes + 7 silent chars.
  const auto c =
      hd::parse_modbus_daq_config({{"transport", "rtu"},
                                   {"baud", 115200},
                                   {"write_read", true},
                                   {"measurement", {{"table", "holding"}, {"address", 10}}}});
  EXPECT_NEAR(c.rtu_wire_time_s(), (15 + 7 + 7) * 10 / 115200.0, 1e-9);
  EXPECT_EQ(c.max_rate_hz, std::floor(115200.0 / 290.0));
}

TEST(ModbusDaqConfig, LoopModeRefusesARateAboveTheDeclaredMaximum) {
  hd::Driver d(hd::make_interface<hd::ModbusDaqDriver, hd::IoThreadDriver>());
  const auto r = d.configure({{"io", "loop"}, {"max_rate_hz", 500}}, 1000.0);
  ASSERT_FALSE(r.ok);
  EXPECT_NE(r.message.find("loop.rate_hz: 1000 Hz is beyond"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("io = \"thread\""), std::string::npos) << r.message;
  EXPECT_TRUE(d.configure({{"io", "thread"}, {"max_rate_hz", 500}}, 10000.0).ok);
}

TEST(ModbusDaqConfig, AStageNamesItsAxesAndTheirRegisterBlocks) {
  const auto c = hd::parse_modbus_daq_config(
      {{"axes", {"x", "y", "z"}}, {"axis_stride", 32}, {"output", {{"address", 1}}}});
  EXPECT_EQ(c.axis_count(), 3u);
  EXPECT_EQ(c.axis_offset(2), 64);
  EXPECT_EQ(c.transactions_per_tick(), 6);
  hd::Driver d(hd::make_interface<hd::ModbusDaqDriver, hd::IoThreadDriver>());
  ASSERT_TRUE(d.configure({{"axes", {"x", "y"}}}, 1000.0).ok);
  EXPECT_EQ(d.axes(), 2u);
  EXPECT_TRUE(d.serves(2).ok);
  EXPECT_FALSE(d.serves(3).ok);
  // Without axes: one axis, as before.
  EXPECT_EQ(hd::parse_modbus_daq_config(json()).axis_count(), 1u);
  // Each axis's frames go over the serial line in turn.
  const json rtu = {{"transport", "rtu"},
                    {"write_read", true},
                    {"measurement", {{"table", "holding"}, {"address", 10}}}};
  json rtu_xy = rtu;
  rtu_xy["axes"] = {"x", "y"};
  EXPECT_NEAR(hd::parse_modbus_daq_config(rtu_xy).rtu_wire_time_s(),
              2.0 * hd::parse_modbus_daq_config(rtu).rtu_wire_time_s(), 1e-12);
}

TEST(ModbusDaqConfig, AStageRefusesAxesItsRegistersCannotHold) {
  EXPECT_EQ(error_of({{"axes", {"x", "X"}}}),
            "driver.modbus.axes: \"X\": 1 to 16 of a-z, 0-9 and _");
  EXPECT_EQ(error_of({{"axes", {"x", "x"}}}), "driver.modbus.axes: \"x\" names two axes");
  EXPECT_EQ(error_of({{"axes", json::array()}}), "driver.modbus.axes: 1 to 6 axis names, got 0");
  EXPECT_EQ(error_of({{"axes", {"a", "b", "c", "d", "e", "f", "g"}}}),
            "driver.modbus.axes: 1 to 6 axis names, got 7");
  EXPECT_EQ(error_of({{"axes", {"x", 2}}}),
            "driver.modbus.axes: every element must be a string, got 2");
  EXPECT_EQ(error_of({{"axis_stride", 16}}),
            "driver.modbus.axis_stride: only with axes (a stage of several axes)");
  EXPECT_EQ(
      error_of({{"axes", {"x", "y"}}, {"axis_stride", 1}, {"measurement", {{"format", "s32"}}}}),
      "driver.modbus.axis_stride: 1 register(s) would overlap the axes' measurement "
      "values of 2 registers");
  EXPECT_EQ(error_of({{"axes", {"x", "y"}}, {"axis_stride", 65535}, {"output", {{"address", 1}}}}),
            "driver.modbus.axes: axis \"y\"'s output would end at register 65536, past the "
            "table (65535): lower axis_stride or the address");
}
