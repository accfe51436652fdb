// The loopback driver's [driver.loopback] table: a misspelt fault key is an error naming it,
// not a fault that silently never fires.
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
