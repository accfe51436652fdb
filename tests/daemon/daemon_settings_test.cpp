// The bench's settings from a configuration file.
#include "hystbench/daemon/daemon_settings.hpp"

#include <gtest/gtest.h>

#include "hystbench/daemon/config.hpp"

namespace hd = hystbench::daemon;

// Tests build BenchSettings directly and the daemon builds them from its configuration: both
// must identify with the same excitation and fit, or a test measures another identification
// than the one a user runs.
TEST(DaemonSettings, IdentifyDefaultsAreTheConfigurationDefaults) {
  const hd::BenchSettings daemon = hd::bench_settings_from(hd::parse_config(""));
  const hd::BenchSettings tests;
  EXPECT_EQ(daemon.identify_model, tests.identify_model);
  EXPECT_EQ(daemon.identify_operators, tests.identify_operators);
  EXPECT_EQ(daemon.identify_dead_zones, tests.identify_dead_zones);
  EXPECT_DOUBLE_EQ(daemon.identify_major_loop_hz, tests.identify_major_loop_hz);
  EXPECT_EQ(daemon.identify_major_loop_cycles, tests.identify_major_loop_cycles);
  EXPECT_DOUBLE_EQ(daemon.identify_precondition_s, tests.identify_precondition_s);
  EXPECT_DOUBLE_EQ(daemon.identify_settle_s, tests.identify_settle_s);
  EXPECT_DOUBLE_EQ(daemon.identify_heldout_fraction, tests.identify_heldout_fraction);
  EXPECT_DOUBLE_EQ(daemon.identify_fit_rate_hz, tests.identify_fit_rate_hz);
}

TEST(DaemonSettings, IdentifyPreconditioningComesFromTheConfiguration) {
  const hd::BenchSettings s =
      hd::bench_settings_from(hd::parse_config("[identify]\nprecondition_s = 3\nsettle_s = 0\n"));
  EXPECT_DOUBLE_EQ(s.identify_precondition_s, 3.0);
  EXPECT_DOUBLE_EQ(s.identify_settle_s, 0.0);
  EXPECT_THROW(hd::parse_config("[identify]\nprecondition_s = 0\n"), hd::ConfigError);
}
