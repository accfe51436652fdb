#pragma once
// What a driver implements: the hooks the framework (driver.hpp) calls, ros2_control style. The
// framework owns the lifecycle state, refuses calls out of order, calls on_error() when write()
// or read() report kFault, keeps the last value and its age across stale reads, counts them and
// puts the reported fault cause in words: a driver does none of that itself.
//
// Lifecycle hooks (not real-time, may allocate and block; each returns a Result naming the
// cause): on_configure(params, rate) -> on_activate() -> [write()/read() per tick] ->
// on_deactivate(). The framework calls them only in this order, and the real-time hooks only
// between on_activate() and on_deactivate().
// Real-time path: write(), read(), safe_state(), on_error(), set_run_active() never throw, never
// allocate, never block longer than the driver's documented bound.
// Units: output in volts (the amplifier command), measurement in micrometres.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>

#include "hystbench/drivers/fault_log.hpp"

namespace hystbench::drivers {

/// Axes a driver may serve in one tick (a stage of several axes: XY, tip-tilt, hexapod).
inline constexpr std::size_t kMaxAxes = 6;

enum class DriverStatus : std::uint8_t {
  kOk = 0,
  kStale,    ///< no new measurement this tick (I/O thread has not delivered yet); value is old
  kTimeout,  ///< the device did not answer in time
  kError,    ///< transfer failed (bad frame, exception reply, ...)
  kFault,    ///< the driver is unusable until it recovers or is re-activated (bus-off, e-stop)
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

/// What the framework and the loop need to know of a configured driver, in one struct. Read
/// after on_configure() and again after on_activate() (a driver may learn its limits there).
struct DriverInfo {
  double max_rate_hz = 0.0;    ///< highest loop rate it holds [Hz]; the framework refuses more
  double output_min_v = 0.0;   ///< output range the hardware accepts [V]
  double output_max_v = 0.0;   ///< [V]
  double safe_output_v = 0.0;  ///< output on a fault, when idle and at deactivation [V]
  double measurement_resolution_um = 0.0;  ///< one count of the measurement [µm]; 0 = unknown
  /// Stale reads in a row that the framework turns into kFault; 0 = no limit.
  std::uint64_t max_stale_reads = 0;
  /// write()/read() block for a round trip: IoThreadDriver, when it wraps the driver, runs them
  /// on its I/O thread (see io_thread_driver.hpp).
  bool io_thread = false;
};

class DriverInterface : public FaultSource {
 public:
  virtual ~DriverInterface() = default;

  /// Validates `params` (the driver's own config table as JSON; unknown keys are errors naming
  /// them) and prepares for a loop at `rate_hz` (> 0: the framework checks, and refuses a rate
  /// above info().max_rate_hz afterwards; a driver refuses earlier to say why).
  virtual Result on_configure(const nlohmann::json& params, double rate_hz) = 0;
  /// Connects and checks the device answers; the output starts at the safe output.
  virtual Result on_activate() = 0;
  /// Drives the safe output and releases the device. Default: safe_state(), a failure if that
  /// is not kOk.
  virtual Result on_deactivate();
  /// Called by the framework in the write()/read() that first reports kFault (real-time path):
  /// drive the safe output now. Must not release what recovery needs: a fault may clear by
  /// itself (a link that reconnects), and on_deactivate() releases. Default: safe_state().
  virtual DriverStatus on_error() noexcept { return safe_state(); }

  /// Commands the output [V] for this tick.
  virtual DriverStatus write(double output_v) noexcept = 0;
  /// kOk with a new measurement in `out` (position_um, response_ticks); kStale when none came
  /// this tick (`out` untouched: the framework repeats the last value and counts its age);
  /// kTimeout, kError or kFault otherwise.
  virtual DriverStatus read(Measurement& out) noexcept = 0;
  /// Drives the configured safe output now.
  virtual DriverStatus safe_state() noexcept = 0;

  /// Axes this configured driver serves, in [1, kMaxAxes]. write() and read() are the first
  /// axis's (the others hold their safe output); write_axes() and read_axes() serve every one.
  /// Valid after on_configure(). Default: 1.
  virtual std::size_t axes() const noexcept { return 1; }
  /// Commands every axis's output [V] for this tick, outputs_v[i] to axis i (axes() values; an
  /// axis without one holds its output). Default (one axis): write(outputs_v[0]).
  virtual DriverStatus write_axes(std::span<const double> outputs_v) noexcept;
  /// Every axis's measurement of this tick into out[i] (axes() values), with read()'s status
  /// for the tick as a whole. Default (one axis): read(out[0]).
  virtual DriverStatus read_axes(std::span<Measurement> out) noexcept;
  /// A run starts (true) or ends (false), called from the loop thread in that tick. For
  /// run-bound outputs such as an amplifier-enable GPIO; the default does nothing.
  virtual void set_run_active(bool /*active*/) noexcept {}

  /// Limits and ranges; valid after on_configure(), refreshed after on_activate().
  virtual DriverInfo info() const noexcept = 0;
  /// The position measured by on_activate() [µm]: what read() repeats until a fresh one.
  virtual double activation_position_um() const noexcept { return 0.0; }
  virtual std::string_view type() const noexcept = 0;
  /// Driver-specific counters and state for `status` (not real-time).
  virtual nlohmann::json diagnostics() const { return nlohmann::json::object(); }
  /// Words for a cause this driver reported with report_fault() (not real-time).
  std::string describe_fault(int cause, std::int64_t detail) const override;

  /// Framework: where report_fault() stores. A wrapper passes it on to the driver it wraps.
  virtual void attach(FaultLog& log) noexcept { faults_ = &log; }

 protected:
  /// Records why this driver reports kFault (real-time safe): `cause` is the driver's own enum
  /// (0 = none), `detail` a number describe_fault() puts in the words.
  template <typename Cause>
  void report_fault(Cause cause, std::int64_t detail = 0) noexcept {
    faults_->store(*this, cause, detail);
  }

 private:
  FaultLog own_faults_;
  FaultLog* faults_ = &own_faults_;
};

}  // namespace hystbench::drivers
