#include "hystbench/daemon/config/config.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "hystbench/daemon/config/daemon_settings.hpp"

namespace hd = hystbench::daemon;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// An example configuration touching every section and key.
constexpr const char* kExample = R"(# hystbenchd configuration
[daemon]
socket_path = "/run/hystbench/hystbench.sock"
log_dir = "/srv/hystbench/logs"
model_dir = "/srv/hystbench/models"
log_level = "debug"

[loop]
rate_hz = 5000
clock = "wall"
realtime = true
priority = 70
cpu = 1
lock_memory = false
overrun_budget = 0
ring_capacity = 131072

[limits]
u_min = -10.0
u_max = 120
slew_v_per_s = 2.5e5
fatal_on_limit = true
y_min = 0.0
y_max = 80.0

[driver]
type = "modbus"

[driver.loopback]
delay_samples = 2

[driver.modbus]
device = "/dev/ttyUSB0"
baud = 115200
registers = { output = 40001, position = 30001 }
calibration = [[0.0, 0.0], [10.0, 1.5]]
installed = 2024-03-01

[actuator]

[identify]
model = "rpi"
operators = 12
dead_zones = 3
amplitude_v = 50
offset_v = 60
frequency_hz = 2.5
cycles = 4
heldout_fraction = 0.3
fit_rate_hz = 1000
extend = false

[pid]
kp = 0.05
ki = 1500
kd = 1e-6
derivative_filter_hz = 800
u_fb_min = -20
u_fb_max = 20
)";

hd::ConfigError error_of(const std::string& text, std::string_view origin = {}) {
  try {
    hd::parse_config(text, origin);
  } catch (const hd::ConfigError& e) {
    return e;
  }
  return hd::ConfigError("no error", "", 0);
}

}  // namespace

TEST(Config, EmptyTextGivesTheDocumentedDefaults) {
  const hd::DaemonConfig c = hd::parse_config("");
  EXPECT_EQ(c.daemon.socket_path, "/run/hystbench/hystbench.sock");
  EXPECT_EQ(c.daemon.log_dir, "/var/lib/hystbench/logs");
  EXPECT_EQ(c.daemon.model_dir, "/var/lib/hystbench/models");
  EXPECT_EQ(c.daemon.log_level, "info");
  EXPECT_EQ(c.loop.rate_hz, 10000.0);
  EXPECT_EQ(c.loop.clock, "wall");
  EXPECT_TRUE(c.loop.realtime);
  EXPECT_EQ(c.loop.priority, 80);
  EXPECT_EQ(c.loop.cpu, -1);
  EXPECT_TRUE(c.loop.lock_memory);
  EXPECT_EQ(c.loop.overrun_budget, 100u);
  EXPECT_EQ(c.loop.ring_capacity, 65536u);
  EXPECT_EQ(c.limits.u_min, 0.0);
  EXPECT_EQ(c.limits.u_max, 150.0);
  EXPECT_EQ(c.limits.slew_v_per_s, 1e6);
  EXPECT_FALSE(c.limits.fatal_on_limit);
  EXPECT_FALSE(c.limits.y_min.has_value());
  EXPECT_FALSE(c.limits.y_max.has_value());
  EXPECT_EQ(c.driver.type, "loopback");
  EXPECT_EQ(c.driver.params(), json::object());
  EXPECT_EQ(c.actuator, json::object());
  EXPECT_EQ(c.identify.model, "mpi");
  EXPECT_EQ(c.identify.operators, 0);
  EXPECT_EQ(c.identify.dead_zones, -1);
  EXPECT_FALSE(c.identify.offset_v.has_value());  // the whole output range
  EXPECT_FALSE(c.identify.amplitude_v.has_value());
  EXPECT_EQ(c.identify.span_v(c.limits.u_min, c.limits.u_max), std::pair(0.0, 150.0));
  EXPECT_EQ(c.pid.u_fb_min, -30.0);
  EXPECT_EQ(c.pid.u_fb_max, 30.0);
  EXPECT_EQ(c.http.listen, "");  // the live view is off
  EXPECT_FALSE(c.http.control);
  EXPECT_EQ(c.http.max_clients, 8);
  EXPECT_EQ(c.http.scope_rate_hz, 500.0);
  // Empty sections are the same as absent ones.
  EXPECT_EQ(hd::to_json(hd::parse_config("[daemon]\n[loop]\n[limits]\n[driver]\n[actuator]\n"
                                         "[identify]\n[pid]\n[http]\n")),
            hd::to_json(c));
}

TEST(Config, ExampleFileParsesWithEveryValue) {
  const fs::path file =
      fs::temp_directory_path() / ("hystbenchd-example-" + std::to_string(::getpid()) + ".toml");
  std::ofstream(file) << kExample;
  const hd::DaemonConfig c = hd::load_config(file);
  fs::remove(file);
  EXPECT_EQ(c.daemon.log_dir, "/srv/hystbench/logs");
  EXPECT_EQ(c.daemon.log_level, "debug");
  EXPECT_EQ(c.loop.rate_hz, 5000.0);
  EXPECT_EQ(c.loop.priority, 70);
  EXPECT_EQ(c.loop.cpu, 1);
  EXPECT_FALSE(c.loop.lock_memory);
  EXPECT_EQ(c.loop.overrun_budget, 0u);
  EXPECT_EQ(c.loop.ring_capacity, 131072u);
  EXPECT_EQ(c.limits.u_min, -10.0);
  EXPECT_EQ(c.limits.u_max, 120.0);
  EXPECT_EQ(c.limits.slew_v_per_s, 2.5e5);
  EXPECT_TRUE(c.limits.fatal_on_limit);
  EXPECT_EQ(c.limits.y_max, 80.0);
  EXPECT_EQ(c.driver.type, "modbus");
  const json modbus = c.driver.params();
  EXPECT_EQ(modbus["device"], "/dev/ttyUSB0");
  EXPECT_EQ(modbus["baud"], 115200);
  EXPECT_EQ(modbus["registers"]["position"], 30001);
  EXPECT_EQ(modbus["calibration"][1][1], 1.5);
  EXPECT_EQ(modbus["installed"], "2024-03-01");
  EXPECT_EQ(c.driver.tables["loopback"]["delay_samples"], 2);
  EXPECT_EQ(c.actuator, json::object());  // only the loopback driver has one
  EXPECT_EQ(c.identify.model, "rpi");
  EXPECT_EQ(c.identify.operators, 12);
  EXPECT_EQ(c.identify.dead_zones, 3);
  EXPECT_EQ(c.identify.amplitude_v.value_or(0.0), 50.0);
  EXPECT_EQ(c.identify.offset_v.value_or(0.0), 60.0);
  EXPECT_EQ(c.identify.frequency_hz, 2.5);
  EXPECT_EQ(c.identify.cycles, 4);
  EXPECT_EQ(c.identify.heldout_fraction, 0.3);
  EXPECT_EQ(c.identify.fit_rate_hz, 1000.0);
  EXPECT_FALSE(c.identify.extend);
  EXPECT_EQ(c.pid.kp, 0.05);
  EXPECT_EQ(c.pid.ki, 1500.0);
  EXPECT_EQ(c.pid.kd, 1e-6);
  EXPECT_EQ(c.pid.derivative_filter_hz, 800.0);
  EXPECT_EQ(c.pid.u_fb_min, -20.0);

  const json j = hd::to_json(c);
  EXPECT_EQ(j["loop"]["rate_hz"], 5000.0);
  EXPECT_EQ(j["limits"]["y_min"], 0.0);
  EXPECT_EQ(j["driver"]["type"], "modbus");
  EXPECT_EQ(j["driver"]["modbus"]["baud"], 115200);
  EXPECT_EQ(j["loop"]["clock"], "wall");
  EXPECT_EQ(j["pid"]["u_fb_max"], 20.0);
  EXPECT_TRUE(hd::to_json(hd::parse_config(""))["limits"]["y_min"].is_null());
}

TEST(Config, EveryErrorNamesItsKey) {
  struct Case {
    const char* toml;
    const char* key;
    const char* message;  // the whole what() when the origin is empty, or its start
  };
  const Case cases[] = {
      {"[loop]\nrate_hz = 50000", "loop.rate_hz", "loop.rate_hz: must be in [1, 20000], got 50000"},
      {"[loop]\nrate_hz = 0.5", "loop.rate_hz", "loop.rate_hz: must be in [1, 20000], got 0.5"},
      {"[loop]\nrate_hz = nan", "loop.rate_hz", "loop.rate_hz: must be in [1, 20000], got nan"},
      {"[loop]\nrate_hz = \"fast\"", "loop.rate_hz", "loop.rate_hz: must be a number, got string"},
      {"[loop]\npriority = 1.5", "loop.priority", "loop.priority: must be an integer, got float"},
      {"[loop]\npriority = 0", "loop.priority", "loop.priority: must be in [1, 99], got 0"},
      {"[loop]\ncpu = -2", "loop.cpu", "loop.cpu: must be in [-1, 1023], got -2"},
      {"[loop]\nrealtime = 1", "loop.realtime",
       "loop.realtime: must be true or false, got integer"},
      {"[loop]\noverrun_budget = -1", "loop.overrun_budget",
       "loop.overrun_budget: must be in [0, 1000000000], got -1"},
      {"[loop]\nring_capacity = 10", "loop.ring_capacity",
       "loop.ring_capacity: must be in [1024, 16777216], got 10"},
      {"[loop]\nrat_hz = 100", "loop.rat_hz", "loop.rat_hz: unknown key (known: rate_hz, "},
      {"[loop]\nclock = \"virtual\"", "loop.clock",
       "loop.clock: must be one of wall, simulated, got \"virtual\""},
      {"[loop]\nclock = true", "loop.clock", "loop.clock: must be a string, got boolean"},
      {"[loop.extra]\na = 1", "loop.extra", "loop.extra: unknown key"},
      {"[lop]\nrate_hz = 100", "lop", "lop: unknown section (known: daemon, loop, "},
      {"rate_hz = 100", "rate_hz", "rate_hz: unknown section"},
      {"loop = 3", "loop", "loop: must be a table ([loop]), got integer"},
      {"[daemon]\nlog_level = \"loud\"", "daemon.log_level",
       "daemon.log_level: must be one of trace, debug, info, warn, error, critical, off, got "
       "\"loud\""},
      {"[daemon]\nsocket_path = \"\"", "daemon.socket_path",
       "daemon.socket_path: must not be empty"},
      {"[daemon]\nlog_dir = 3", "daemon.log_dir", "daemon.log_dir: must be a string, got integer"},
      {"[limits]\nu_min = 10\nu_max = 5", "limits.u_max",
       "limits.u_max: must be greater than limits.u_min (10), got 5"},
      {"[limits]\nslew_v_per_s = 0", "limits.slew_v_per_s",
       "limits.slew_v_per_s: must be > 0, got 0"},
      {"[limits]\nfatal_on_limit = \"yes\"", "limits.fatal_on_limit",
       "limits.fatal_on_limit: must be true or false, got string"},
      {"[limits]\ny_min = 0", "limits.y_max",
       "limits.y_max: limits.y_min and limits.y_max must be given together"},
      {"[limits]\ny_min = 5\ny_max = 5", "limits.y_max",
       "limits.y_max: must be greater than limits.y_min (5), got 5"},
      {"[driver]\ntype = \"Mod Bus\"", "driver.type", "driver.type: must be a driver name"},
      {"[driver]\nbaud = 9600", "driver.baud", "driver.baud: unknown key"},
      {"[identify]\nmodel = \"xyz\"", "identify.model", "identify.model: must be one of pi, mpi"},
      {"[identify]\ndead_zones = -2", "identify.dead_zones",
       "identify.dead_zones: must be in [-1, 50], got -2"},
      {"[identify]\namplitude_v = 100", "identify.amplitude_v",
       "identify.amplitude_v: offset_v +- amplitude_v = [-25, 175] V must lie within "
       "[limits.u_min, limits.u_max] = [0, 150]"},
      {"[identify]\nfrequency_hz = 1000", "identify.frequency_hz",
       "identify.frequency_hz: must be in (0, 500], got 1000"},
      {"[identify]\ncycles = 0", "identify.cycles", "identify.cycles: must be in [1, 1000], got 0"},
      {"[pid]\nkp = -1", "pid.kp", "pid.kp: must be >= 0, got -1"},
      {"[pid]\nki = inf", "pid.ki", "pid.ki: must be >= 0, got inf"},
      {"[limits]\nu_min = -inf", "limits.u_min", "limits.u_min: must be a finite number, got -inf"},
      {"[identify]\namplitude_v = 0", "identify.amplitude_v",
       "identify.amplitude_v: must be in (0, 150], got 0"},
      {"[pid]\nderivative_filter_hz = 6000", "pid.derivative_filter_hz",
       "pid.derivative_filter_hz: must be below loop.rate_hz / 2 = 5000 Hz, got 6000"},
      {"[pid]\nu_fb_min = 5\nu_fb_max = -5", "pid.u_fb_max",
       "pid.u_fb_max: must be at least pid.u_fb_min (5), got -5"},
      {"[http]\nlisten = \"localhost\"", "http.listen",
       "http.listen: must be HOST:PORT (e.g. 127.0.0.1:8080), got 'localhost'"},
      {"[http]\nlisten = \"127.0.0.1:99999\"", "http.listen",
       "http.listen: the port must be a number in [0, 65535] (0: a free one), got '99999'"},
      {"[http]\nmax_clients = 0", "http.max_clients",
       "http.max_clients: must be in [2, 64], got 0"},
      {"[http]\ncontrol = \"yes\"", "http.control",
       "http.control: must be true or false, got string"},
  };
  for (const auto& c : cases) {
    const hd::ConfigError e = error_of(c.toml);
    EXPECT_EQ(e.key(), c.key) << c.toml;
    EXPECT_EQ(std::string(e.what()).rfind(c.message, 0), 0u)
        << c.toml << "\n  got: " << e.what() << "\n  expected: " << c.message;
  }
  const std::string long_path(120, 'x');
  EXPECT_EQ(error_of("[daemon]\nsocket_path = \"/" + long_path + "\"").key(), "daemon.socket_path");
}

TEST(Config, ErrorsFromAFileCarryFileAndLine) {
  const hd::ConfigError e = error_of("[daemon]\nlog_level = \"info\"\n\n[loop]\nrate_hz = 50000\n",
                                     "/etc/hystbench/hystbenchd.toml");
  EXPECT_STREQ(e.what(),
               "/etc/hystbench/hystbenchd.toml:5: loop.rate_hz: must be in [1, 20000], got 50000");
  EXPECT_EQ(e.line(), 5);
  // A cross-key check on a key that is absent has no line.
  const hd::ConfigError y = error_of("[limits]\ny_min = 1\n", "f.toml");
  EXPECT_STREQ(y.what(),
               "f.toml: limits.y_max: limits.y_min and limits.y_max must be given together");
}

TEST(Config, SyntaxErrorsAndUnreadableFilesAreConfigErrors) {
  const hd::ConfigError e = error_of("[loop]\nrate_hz = = 3\n", "x.toml");
  EXPECT_EQ(e.key(), "");
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(std::string(e.what()).rfind("x.toml:2:", 0), 0u) << e.what();
  try {
    hd::load_config("/nonexistent/hystbenchd.toml");
    FAIL() << "no error";
  } catch (const hd::ConfigError& err) {
    EXPECT_NE(std::string(err.what()).find("/nonexistent/hystbenchd.toml"), std::string::npos);
  }
}

TEST(Config, ExcitationDefaultsFollowTheOutputLimits) {
  const hd::DaemonConfig c = hd::parse_config("[limits]\nu_min = -10\nu_max = 110\n");
  EXPECT_EQ(c.identify.span_v(c.limits.u_min, c.limits.u_max), std::pair(-10.0, 110.0));
  // config.get shows the excitation as it will run.
  EXPECT_EQ(hd::to_json(c)["identify"]["offset_v"], 50.0);
  EXPECT_EQ(hd::to_json(c)["identify"]["amplitude_v"], 60.0);
  // Half given: the other half from the limits, and the span checked against them.
  const hd::DaemonConfig o =
      hd::parse_config("[limits]\nu_min = -10\nu_max = 110\n[identify]\namplitude_v = 30\n");
  EXPECT_EQ(o.identify.span_v(o.limits.u_min, o.limits.u_max), std::pair(20.0, 80.0));
  EXPECT_THROW(hd::parse_config("[limits]\nu_min = -10\nu_max = 110\n[identify]\noffset_v = 40\n"),
               hd::ConfigError);
}

TEST(Config, TomlToJsonConvertsEveryType) {
  const json j = hd::toml_to_json(R"(
title = "bench"
count = 3
ratio = 0.25
on = false
list = [1, 2.5, "x"]
when = 1979-05-27T07:32:00Z
day = 1979-05-27
at = 07:32:00
[nested.deeper]
k = -7
[[runs]]
id = "a"
[[runs]]
id = "b"
)");
  EXPECT_EQ(j["title"], "bench");
  EXPECT_TRUE(j["count"].is_number_integer());
  EXPECT_EQ(j["count"], 3);
  EXPECT_EQ(j["ratio"], 0.25);
  EXPECT_EQ(j["on"], false);
  EXPECT_EQ(j["list"], json::parse(R"([1, 2.5, "x"])"));
  EXPECT_EQ(j["when"], "1979-05-27T07:32:00Z");
  EXPECT_EQ(j["day"], "1979-05-27");
  EXPECT_EQ(j["at"], "07:32:00");
  EXPECT_EQ(j["nested"]["deeper"]["k"], -7);
  EXPECT_EQ(j["runs"][1]["id"], "b");
  EXPECT_THROW(hd::toml_to_json("a = "), hd::ConfigError);
}

TEST(Config, EveryShippedConfigFileLoads) {
  const fs::path dir = fs::path(HYSTBENCH_SOURCE_DIR) / "config";
  int files = 0;
  if (fs::is_directory(dir)) {
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.path().extension() != ".toml") continue;
      ++files;
      EXPECT_NO_THROW(hd::load_config(entry.path())) << entry.path();
    }
  }
  if (files == 0) GTEST_SKIP() << "no config/*.toml in " << dir;
}

// The simulated clock is for the loopback only: the simulated actuator is the one plant that can
// follow a virtual clock. With another driver the key is refused where it stands, saying why.
TEST(Config, TheSimulatedClockIsForTheLoopbackDriverOnly) {
  const hd::DaemonConfig c = hd::parse_config("[loop]\nclock = \"simulated\"\n");
  EXPECT_EQ(c.loop.clock, "simulated");
  EXPECT_EQ(hd::to_json(c)["loop"]["clock"], "simulated");
  EXPECT_EQ(hd::bench_settings_from(c).loop.clock, hd::LoopClock::kSimulated);
  EXPECT_EQ(hd::bench_settings_from(hd::parse_config("")).loop.clock, hd::LoopClock::kWall);

  const hd::ConfigError e = error_of(
      "[loop]\nrate_hz = 5000\nclock = \"simulated\"\n\n[driver]\ntype = \"modbus\"\n", "b.toml");
  EXPECT_EQ(e.key(), "loop.clock");
  EXPECT_EQ(e.line(), 3);
  EXPECT_STREQ(
      e.what(),
      "b.toml:3: loop.clock: \"simulated\" needs driver.type = \"loopback\" (the simulated "
      "actuator is the only plant that can follow a virtual clock), got driver.type = "
      "\"modbus\"");
  EXPECT_EQ(hd::clock_conflict("simulated", "can"), hd::clock_conflict("simulated", "can"));
  EXPECT_NE(hd::clock_conflict("simulated", "can").find("\"can\""), std::string::npos);
  EXPECT_EQ(hd::clock_conflict("wall", "can"), "");
  EXPECT_EQ(hd::clock_conflict("simulated", "loopback"), "");
}

// The [actuator] table is the loopback's simulated actuator: checked with the rest of the file
// by the simulator's own reader, its errors named by file, line and key path: the offending
// node's line (an array element's own line), its table's for a key that is missing.
TEST(Config, TheActuatorTableIsCheckedWithFileLineAndKey) {
  struct Case {
    const char* toml;
    const char* key;
    int line;
    const char* message;  // the start of what()
  };
  const Case cases[] = {
      {"[loop]\nrate_hz = 10000\n\n[actuator.dynamcs]\nenabled = true\n", "actuator.dynamcs", 4,
       "a.toml:4: actuator.dynamcs: unknown key (valid: input, hysteresis, "},
      {"[actuator.creep]\nenabled = \"yes\"\n", "actuator.creep.enabled", 2,
       "a.toml:2: actuator.creep.enabled: expected true or false, got \"yes\""},
      {"[actuator.creep]\nenable = true\n", "actuator.creep.enable", 2,
       "a.toml:2: actuator.creep.enable: unknown key (valid: enabled, "},
      {"[actuator.dynamics]\nenabled = true\nnatural_frequencies_hz = [\n  3000.0,\n  -1.0,\n]\n",
       "actuator.dynamics.natural_frequencies_hz[1]", 5,
       "a.toml:5: actuator.dynamics.natural_frequencies_hz[1]: must be > 0"},
      {"[actuator.dynamics]\nenabled = true\nmode_gains = [0.5, 0.3, 0.2]\n",
       "actuator.dynamics.mode_gains", 3,
       "a.toml:3: actuator.dynamics.mode_gains: has 3 entries, dynamics.natural_frequencies_hz "
       "has 2"},
      // The key at fault is missing (its default does not fit the others): its table's line.
      {"[actuator]\n\n[actuator.dynamics]\nenabled = true\nnatural_frequencies_hz = [1000.0]\n",
       "actuator.dynamics.damping_ratios", 3,
       "a.toml:3: actuator.dynamics.damping_ratios: has 2 entries, "
       "dynamics.natural_frequencies_hz has 1"},
      // A key of another form of its effect: named, not ignored.
      {"[actuator.creep]\nenabled = true\n\ngains_um_per_v = [0.1]\n",
       "actuator.creep.gains_um_per_v", 4,
       "a.toml:4: actuator.creep.gains_um_per_v: applies to creep.law = \"input_lags\""},
      {"[actuator.input]\nmin_v = 10.0\nmax_v = 5.0\n", "actuator.input.max_v", 3,
       "a.toml:3: actuator.input.max_v: must be greater than input.min_v"},
      {"[actuator.delay]\nenabled = true\ndelay_s = 2.0\n", "actuator.delay.delay_s", 3,
       "a.toml:3: actuator.delay.delay_s: must be in [0, 1] s"},
      {"[actuator]\ndynamics = { enabled = true, mode_gains = [1.0] }\n",
       "actuator.dynamics.mode_gains", 2, "a.toml:2: actuator.dynamics.mode_gains: has 1 "},
      // A stage of several axes: its own keys, named at their line.
      {"[driver]\ntype = \"loopback\"\n[driver.loopback.stage]\naxes = []\n",
       "driver.loopback.stage.axes", 4,
       "a.toml:4: driver.loopback.stage.axes: a stage has 1 to 6 axes"},
      // ... and its axes' actuators in it: an [actuator] beside it would be a second truth.
      {"[driver]\ntype = \"loopback\"\n[driver.loopback.stage]\n[actuator.creep]\n"
       "enabled = false\n",
       "actuator", 4, "a.toml:4: actuator: [driver.loopback.stage] simulates each axis's actuator"},
      // The loopback driver's own table, when it names the actuator.
      {"[driver.loopback.actuator.sensor_filter]\nenabled = true\ndamping_ratio = 0.0\n",
       "driver.loopback.actuator.sensor_filter.damping_ratio", 3,
       "a.toml:3: driver.loopback.actuator.sensor_filter.damping_ratio: must be > 0"},
      // Another driver simulates nothing: a table there would do nothing.
      {"[driver]\ntype = \"modbus\"\n[actuator.creep]\nenabled = false\n", "actuator", 3,
       "a.toml:3: actuator: only the loopback driver simulates an actuator, driver.type is "
       "\"modbus\""},
  };
  for (const auto& c : cases) {
    const hd::ConfigError e = error_of(c.toml, "a.toml");
    EXPECT_EQ(e.key(), c.key) << c.toml << "\n  got: " << e.what();
    EXPECT_EQ(e.line(), c.line) << c.toml << "\n  got: " << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(c.message, 0), 0u)
        << c.toml << "\n  got: " << e.what() << "\n  expected: " << c.message;
  }
  // A valid table is kept as it is, integers and all (a seed is unsigned).
  const hd::DaemonConfig ok = hd::parse_config(
      "[actuator.sensor_noise]\nenabled = true\nseed = 7\n[actuator.creep]\nenabled = false\n");
  EXPECT_EQ(ok.actuator["sensor_noise"]["seed"], 7);
  EXPECT_EQ(hd::bench_settings_from(ok).driver_params["actuator"], ok.actuator);
  // An empty [actuator] table goes with any driver (config/hystbenchd.toml has one).
  EXPECT_NO_THROW(hd::parse_config("[driver]\ntype = \"modbus\"\n[actuator]\n"));
}
