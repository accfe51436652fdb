// The loopback driver's [driver.loopback] table: a misspelt fault key is an error naming it,
// not a fault that silently never fires; a rate above its max_rate_hz is refused.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "hystbench/drivers/driver.hpp"

namespace hd = hystbench::drivers;
using nlohmann::json;

TEST(LoopbackDriver, FaultKeysAreCheckedAndNamed) {
  auto driver = hd::make_driver("loopback");
  EXPECT_TRUE(driver->configure({{"faults", {{"nan_at_tick", 10}}}}, 1000.0).ok);
  driver = hd::make_driver("loopback");
  hd::Result r = driver->configure({{"faults", {{"nan_at_tik", 10}}}}, 1000.0);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("faults.nan_at_tik"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("stuck_at_tick"), std::string::npos) << r.message;
  driver = hd::make_driver("loopback");
  r = driver->configure({{"faults", {{"stuck_at_tick", -3}}}}, 1000.0);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("faults.stuck_at_tick"), std::string::npos) << r.message;
  driver = hd::make_driver("loopback");
  EXPECT_FALSE(driver->configure({{"faults", 5}}, 1000.0).ok);
}

TEST(LoopbackDriver, RefusesARateAboveItsMaxRate) {
  auto driver = hd::make_driver("loopback");
  const hd::Result r = driver->configure({{"max_rate_hz", 5000}}, 10000.0);
  EXPECT_EQ(r.message,
            "loop.rate_hz: 10000 Hz is beyond what the loopback driver holds as configured (at "
            "most 5000 Hz)");
  EXPECT_TRUE(driver->configure({{"max_rate_hz", 5000}}, 5000.0).ok);
}
