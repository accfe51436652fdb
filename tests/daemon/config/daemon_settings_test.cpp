// The bench's settings from a configuration file.
#include "hystbench/daemon/config/daemon_settings.hpp"

#include <gtest/gtest.h>

#include "hystbench/daemon/config/config.hpp"

namespace hd = hystbench::daemon;

// Tests build BenchSettings directly and the daemon builds them from its configuration: both
// must identify with the same excitation and fit, or a test measures another identification
// than the one a user runs.
TEST(DaemonSettings, IdentifyAndPidDefaultsAreTheConfigurationDefaults) {
  const hd::BenchSettings daemon = hd::bench_settings_from(hd::parse_config(""));
  const hd::BenchSettings tests;
  hd::DaemonConfig from_daemon, from_tests;
  from_daemon.identify = daemon.identify;
  from_daemon.pid = daemon.pid;
  from_tests.identify = tests.identify;
  from_tests.pid = tests.pid;
  // Every key of both sections, as config.get shows them.
  EXPECT_EQ(hd::to_json(from_daemon)["identify"], hd::to_json(from_tests)["identify"]);
  EXPECT_EQ(hd::to_json(from_daemon)["pid"], hd::to_json(from_tests)["pid"]);
  // And a configured key reaches the bench under its own name.
  const hd::BenchSettings s = hd::bench_settings_from(
      hd::parse_config("[identify]\nfrequency_hz = 0.5\ncycles = 2\n[pid]\nu_fb_min = -5\n"));
  EXPECT_EQ(s.identify.frequency_hz, 0.5);
  EXPECT_EQ(s.identify.cycles, 2);
  EXPECT_EQ(s.pid.u_fb_min, -5.0);
}

TEST(DaemonSettings, IdentifyPreconditioningComesFromTheConfiguration) {
  const hd::BenchSettings s =
      hd::bench_settings_from(hd::parse_config("[identify]\nprecondition_s = 3\nsettle_s = 0\n"));
  EXPECT_DOUBLE_EQ(s.identify.precondition_s, 3.0);
  EXPECT_DOUBLE_EQ(s.identify.settle_s, 0.0);
  EXPECT_THROW(hd::parse_config("[identify]\nprecondition_s = 0\n"), hd::ConfigError);
}
