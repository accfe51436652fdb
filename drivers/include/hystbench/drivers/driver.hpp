#pragma once
// One interface for every I/O path between the bench loop and an actuator (ros2_control style).
//
// Lifecycle (not real-time, may allocate and block; each returns a Result naming the cause):
//   configure(params, rate) -> activate() -> [loop: write()/read() per tick] -> deactivate()
//   on_error() is called once after a fault; it must leave the output safe.
// Real-time path: write(), read(), safe_state() never throw, never allocate, never block longer
// than the driver's documented bound; they return a DriverStatus.
// Units: output in volts (the amplifier command), measurement in micrometres.
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace hystbench::drivers {

enum class DriverStatus : std::uint8_t {
  kOk = 0,
  kStale,    ///< no new measurement this tick (I/O thread has not delivered yet); value is old
  kTimeout,  ///< the device did not answer in time
  kError,    ///< transfer failed (bad frame, exception reply, ...)
  kFault,    ///< the driver is unusable until on_error()/re-activation (bus-off, peer gone, e-stop)
};
std::string_view to_string(DriverStatus s) noexcept;

struct Measurement {
  double position_um = 0.0;     ///< displacement [µm]
  std::uint64_t age_ticks = 0;  ///< ticks since the value was taken (0 = fresh this tick)
  /// Ticks between the write() whose output this value answers and this tick (0 = this tick's
  /// write; a thread-mode Modbus exchange or a CAN feedback frame answers an earlier one).
  std::uint64_t response_ticks = 0;
};

/// Outcome of a lifecycle call: ok, or a message that names the cause.
struct Result {
  bool ok = true;
  std::string message;
  static Result success() { return {}; }
  static Result failure(std::string why) { return {false, std::move(why)}; }
  explicit operator bool() const noexcept { return ok; }
};

class Driver {
 public:
  virtual ~Driver() = default;

  /// Validates `params` (the driver's own config table as JSON; unknown keys are errors naming
  /// them) and prepares for a loop at `rate_hz`. Refuses a rate it cannot hold.
  virtual Result configure(const nlohmann::json& params, double rate_hz) = 0;
  virtual Result activate() = 0;
  virtual Result deactivate() = 0;
  /// After a fault: drive the safe output if at all possible, release what can be released.
  virtual Result on_error() = 0;

  /// Commands the output [V] for this tick.
  virtual DriverStatus write(double output_v) noexcept = 0;
  /// The measurement for this tick.
  virtual DriverStatus read(Measurement& out) noexcept = 0;
  /// Drives the configured safe output now.
  virtual DriverStatus safe_state() noexcept = 0;
  /// A run starts (true) or ends (false), called from the loop thread in that tick (real-time
  /// path). For run-bound outputs such as an amplifier-enable GPIO; the default does nothing.
  virtual void set_run_active(bool /*active*/) noexcept {}

  /// Highest loop rate this driver can hold [Hz].
  virtual double max_rate_hz() const noexcept = 0;
  /// Output range the hardware accepts [V].
  virtual double output_min_v() const noexcept = 0;
  virtual double output_max_v() const noexcept = 0;
  /// The configured safe output [V].
  virtual double safe_output_v() const noexcept = 0;
  /// One count of the measurement [µm] (the smallest change it can show); 0 = unknown.
  virtual double measurement_resolution_um() const noexcept { return 0.0; }
  virtual std::string_view type() const noexcept = 0;
  /// Driver-specific counters and state for `status` (not real-time).
  virtual nlohmann::json diagnostics() const { return nlohmann::json::object(); }
};

/// One row of the driver table: how to make a backend and what it is.
struct DriverBackend {
  std::string_view type;
  std::string_view description;
  std::unique_ptr<Driver> (*create)();
};

/// Every compiled-in backend.
const std::vector<DriverBackend>& driver_backends();
/// Creates the backend named `type`; throws std::invalid_argument listing the valid names.
std::unique_ptr<Driver> make_driver(std::string_view type);

}  // namespace hystbench::drivers
