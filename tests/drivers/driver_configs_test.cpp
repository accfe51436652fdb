// The shipped driver configs (config/modbus-*.toml, config/can.toml) load and their driver
// tables pass the drivers' own validation at the configured loop rate, with their axes.
#include <gtest/gtest.h>

#include <filesystem>

#include "hystbench/daemon/config/config.hpp"
#include "hystbench/daemon/config/daemon_settings.hpp"
#include "hystbench/drivers/driver.hpp"

namespace hdm = hystbench::daemon;
namespace hd = hystbench::drivers;

TEST(DriverConfigs, ShippedExamplesConfigureTheirDrivers) {
  for (const char* name : {"modbus-tcp.toml", "modbus-rtu.toml", "modbus-xy.toml", "can.toml"}) {
    SCOPED_TRACE(name);
    const auto path = std::filesystem::path(HYSTBENCH_SOURCE_DIR) / "config" / name;
    const hdm::BenchSettings s = hdm::bench_settings_from(hdm::load_config(path));
    auto driver = hd::make_driver(s.driver_type);
    const hd::Result r = driver->configure(s.driver_params, s.loop.rate_hz);
    EXPECT_TRUE(r.ok) << r.message;
    EXPECT_LE(s.loop.limits.u_max, driver->output_max_v());
    // The bench drives as many axes as the driver serves, named as the config names them.
    EXPECT_EQ(driver->axes(), std::max<std::size_t>(1, s.axes.size()));
  }
  const hdm::BenchSettings xy = hdm::bench_settings_from(
      hdm::load_config(std::filesystem::path(HYSTBENCH_SOURCE_DIR) / "config/modbus-xy.toml"));
  EXPECT_EQ(xy.axes, (std::vector<std::string>{"x", "y"}));
}

TEST(DriverConfigs, EveryBackendIsInTheTable) {
  for (const char* type : {"loopback", "modbus", "can"}) {
    EXPECT_EQ(hd::make_driver(type)->type(), type);
  }
  try {
    hd::make_driver("profibus");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("modbus, can"), std::string::npos) << e.what();
  }
}
