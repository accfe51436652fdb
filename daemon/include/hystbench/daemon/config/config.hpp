#pragma once
// The daemon's configuration file (TOML). Every section and key is optional; a missing one
// takes the default below. An unknown key, a wrong type or a value out of range throws
// ConfigError whose message starts with the key path, e.g.
//   loop.rate_hz: must be in [1, 20000], got 50000
// (prefixed with "<file>:<line>: " when it comes from load_config()).
//
//   [daemon]   socket_path, log_dir, model_dir, log_level
//   [loop]     rate_hz, clock, realtime, priority, cpu, lock_memory, overrun_budget, ring_capacity,
//              stuck_sensor_ms, stuck_sensor_span, feedforward_bandwidth_hz
//   [limits]   u_min, u_max, slew_v_per_s, fatal_on_limit, y_min, y_max
//   [driver]   type, plus one sub-table per driver ([driver.loopback], [driver.modbus], ...)
//              kept as JSON and validated by the driver itself
//   [actuator] the simulated actuator's truth (loopback driver only; also
//              [driver.loopback.actuator]), checked with sim::from_json: its errors name
//              "actuator.<key path>" and the line of the offending node (of its table when the
//              key is missing). A non-empty [actuator] with another driver is an error (it would
//              do nothing).
//   [identify] model, operators, dead_zones, amplitude_v, offset_v, frequency_hz, cycles,
//              precondition_s, settle_s, heldout_fraction, fit_rate_hz
//   [pid]      kp, ki, kd, bandwidth_hz, output_filter_hz, derivative_filter_hz, u_fb_min,
//              u_fb_max
//   [http]     listen, control, token_file, max_clients, scope_rate_hz (the live view)
// Not real-time safe (allocates, throws); read once at start-up.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace hystbench::daemon {

/// A bad configuration: what() names the key path (and file:line when known).
class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& what, std::string key, int line)
      : std::runtime_error(what), key_(std::move(key)), line_(line) {}
  /// Dotted key path, e.g. "loop.rate_hz"; empty for a TOML syntax error.
  const std::string& key() const noexcept { return key_; }
  /// 1-based line in the TOML text; 0 when not known (a missing key, a cross-key check).
  int line() const noexcept { return line_; }

 private:
  std::string key_;
  int line_;
};

struct DaemonSection {
  std::string socket_path = "/run/hystbench/hystbench.sock";  ///< at most 107 bytes
  std::string log_dir = "/var/lib/hystbench/logs";
  std::string model_dir = "/var/lib/hystbench/models";
  std::string log_level = "info";  ///< trace | debug | info | warn | error | critical | off
};

struct LoopSection {
  double rate_hz = 10000.0;  ///< [1, 20000] Hz
  /// "wall": ticks on CLOCK_MONOTONIC deadlines. "simulated" (loopback driver only): virtual time,
  /// one period per tick, runs tick as fast as they compute (bench_loop.hpp).
  std::string clock = "wall";
  bool realtime = true;     ///< try SCHED_FIFO (degraded, not fatal, when not permitted)
  int priority = 80;        ///< SCHED_FIFO priority [1, 99]
  int cpu = -1;             ///< CPU to pin the loop thread to; -1 = none; [0, 1023]
  bool lock_memory = true;  ///< mlockall(MCL_CURRENT | MCL_FUTURE)
  /// Overruns tolerated per run, counted in total (not consecutively): the run ends with a
  /// fault at overrun number overrun_budget + 1. 0 = the first overrun ends it. [0, 1e9]
  std::uint64_t overrun_budget = 100;
  /// Sample-log ring records [1024, 2^24], rounded up to a power of two.
  std::size_t ring_capacity = std::size_t{1} << 16;
  /// A fresh reading that stays bit for bit the same for this long [ms] after the output has
  /// moved stuck_sensor_span of [u_min, u_max] (at least two sensor counts at the y/u range's
  /// gain), plus the response latency, faults the run (frozen sensor; stuck_sensor_detector.hpp).
  /// [0, 10000]; 0 = off.
  double stuck_sensor_ms = 20.0;
  double stuck_sensor_span = 0.02;  ///< (0, 1]
  /// Roll-off of the feedforward's dynamics inversion [Hz] (>= 0; 0 = min(loop rate / 4, twice
  /// the model's natural frequency)); a model file's dynamics.feedforward_bandwidth_hz wins.
  double feedforward_bandwidth_hz = 0.0;
};

struct LimitsSection {
  double u_min = 0.0;           ///< output clamp [V], finite, u_min < u_max
  double u_max = 150.0;         ///< [V]
  double slew_v_per_s = 1e6;    ///< output rate limit (0, 1e12] V/s
  bool fatal_on_limit = false;  ///< true: a clamped or rate-limited sample ends the run (fault)
  /// Reference range [µm]; both or neither; unset = the reference is not limited.
  std::optional<double> y_min;
  std::optional<double> y_max;
};

struct DriverSection {
  std::string type = "loopback";  ///< [a-z0-9_-]+, checked against the backends by the driver
  /// Every [driver.<name>] sub-table as JSON, by name: {"loopback": {...}, "modbus": {...}}.
  nlohmann::json tables = nlohmann::json::object();
  /// The sub-table of the selected type ({} when absent), for Driver::configure().
  nlohmann::json params() const;
};

struct IdentifySection {
  std::string model = "mpi";  ///< pi | mpi | cpi | rpi | preisach | auto
  int operators = 0;          ///< plays [0, 100]; 0 = chosen by held-out error
  int dead_zones = -1;        ///< dead zones per side [-1, 50]; -1 = chosen by held-out error
  /// Excitation u = offset_v + amplitude_v * wave, inside [u_min, u_max] [V]; absent: half the
  /// range and its middle (the whole range).
  std::optional<double> amplitude_v;
  std::optional<double> offset_v;
  double frequency_hz = 1.0;  ///< (0, loop.rate_hz / 20]
  int cycles = 3;             ///< [1, 1000]
  /// Sweep to u_max and u_min before the recorded excitation [s], (0, 60]: every
  /// identification starts from the same hysteresis state whatever ran before.
  double precondition_s = 1.0;
  double settle_s = 5.0;  ///< hold at mid-range before the sweep [s], [0, 600]
  /// End of the excitation kept out of the fit [0, 0.9]. Small: the excitation ends with holds at
  /// the range ends, which the model needs to see; held out they only judge the model order.
  double heldout_fraction = 0.1;
  double fit_rate_hz = 2000.0;  ///< records are block-averaged to this rate for the fit
  /// After the fit, diagnose the record with the model and adopt the extended model (delay,
  /// dynamics, creep, rate law, asymmetry) when its verified tracking is better.
  bool extend = true;

  /// The excitation's lowest and highest input within output limits [u_min, u_max] [V].
  std::pair<double, double> span_v(double u_min, double u_max) const {
    const double offset = offset_v.value_or(0.5 * (u_min + u_max));
    const double amplitude = amplitude_v.value_or(0.5 * (u_max - u_min));
    return {offset - amplitude, offset + amplitude};
  }
};

struct PidSection {
  /// Gains; all three absent = the loop designed per run from the stage's measured frequency
  /// responses (compensation/loop_design.hpp); any given = the given ones, the others 0, checked
  /// against the targets below on those responses. In V per µm of error at the drive's mean
  /// slope: behind the model's inverse they act through its local slope.
  std::optional<double> kp;            ///< [V/µm] >= 0
  std::optional<double> ki;            ///< [V/(µm s)] >= 0
  std::optional<double> kd;            ///< [V s/µm] >= 0
  std::optional<double> bandwidth_hz;  ///< the designed loop's crossover at most this; absent: none
  /// Low-pass of the feedback output for given gains [Hz]; absent = none; below loop.rate_hz / 2.
  std::optional<double> output_filter_hz;
  double derivative_filter_hz = 0.0;  ///< 0 = unfiltered; below loop.rate_hz / 2
  double u_fb_min = -30.0;            ///< clamp of the feedback's share of the drive [V]
  double u_fb_max = 30.0;
  /// The loop's targets, met on every measured response: the design's and the check of given
  /// gains.
  double gain_margin_db = 6.0;       ///< at least, >= 0
  double phase_margin_deg = 45.0;    ///< at least, in [0, 90)
  double peak_sensitivity_db = 6.0;  ///< at most, > 0
  /// Run given gains that break the targets (refused otherwise).
  bool force = false;
  /// Fault a run whose loop oscillates (loop/oscillation_detector.hpp) to the safe output.
  bool oscillation_trip = true;
};

/// The live view in a browser (docs/reference/web-view.md). Off while listen is empty.
struct HttpSection {
  std::string listen;    ///< "HOST:PORT" (port 0: a free one), "" = off
  bool control = false;  ///< runs may be started and stopped from the page, with the token
  /// The token's file; "" = $CREDENTIALS_DIRECTORY/http-token (systemd LoadCredential=).
  std::string token_file;
  std::int64_t max_clients = 8;  ///< connections served at once, [2, 64]
  double scope_rate_hz = 500.0;  ///< scope samples per second [10, 2000], at most the loop rate
};

/// listen's host and port, or why it is not "HOST:PORT" with a port in [0, 65535].
struct ListenAddress {
  std::string host;
  int port = 0;
  std::string error;  ///< empty when valid
};
ListenAddress parse_listen_address(std::string_view text);

struct DaemonConfig {
  DaemonSection daemon;
  LoopSection loop;
  LimitsSection limits;
  DriverSection driver;
  nlohmann::json actuator = nlohmann::json::object();  ///< the [actuator] table as JSON
  IdentifySection identify;
  PidSection pid;
  HttpSection http;
};

/// Why `clock` cannot run with `driver_type` (empty when it can): the simulated clock needs the
/// loopback driver, the only plant that follows a virtual clock.
std::string clock_conflict(std::string_view clock, std::string_view driver_type);

/// Parses TOML text. `origin` (a file name) prefixes messages as "origin:line: ".
DaemonConfig parse_config(std::string_view toml_text, std::string_view origin = {});
/// Reads and parses a file; a file that cannot be read is a ConfigError too.
DaemonConfig load_config(const std::filesystem::path& path);

/// The effective configuration with every default filled in, sections and keys as in the file
/// (for config.get); unset optionals are null.
nlohmann::json to_json(const DaemonConfig& config);

/// A whole TOML document as JSON: tables -> objects, arrays -> arrays, integers -> uint64 (>= 0)
/// or int64, floats -> double, dates and times -> ISO 8601 strings. Throws ConfigError on bad
/// syntax.
nlohmann::json toml_to_json(std::string_view toml_text);

}  // namespace hystbench::daemon
