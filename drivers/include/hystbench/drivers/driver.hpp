#pragma once
// The framework side of a driver (as ros2_control's System wraps a SystemInterface): the bench
// talks to this class only; it owns a DriverInterface (driver_interface.hpp) and
//   - owns the lifecycle state and refuses calls out of order (write()/read() while not active
//     return kFault without reaching the driver; activate() before configure() fails);
//   - refuses a loop rate above DriverInfo::max_rate_hz, after configure and after activate;
//   - turns an exception a lifecycle hook throws into a failed Result naming the driver;
//   - calls the driver's on_error() in the write()/read() that first reports kFault, once per
//     fault (a fault ends with the next fresh read);
//   - keeps the last value across stale reads: age_ticks, the stale count, and kFault after
//     DriverInfo::max_stale_reads stale reads in a row;
//   - turns the stored fault cause into words: diagnostics()["last_fault"];
//   - serves the axes of a driver of several (write_axes()/read_axes()), their last values kept
//     per axis, and refuses a configuration that names more axes than the driver serves.
// Real-time path: write(), read(), safe_state(), set_run_active() and the getters: no allocation,
// no lock, no exception; they add a few atomic stores to the driver's own bound.
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>

#include "hystbench/drivers/driver_interface.hpp"
#include "hystbench/drivers/driver_registry.hpp"

namespace hystbench::drivers {

class Driver final : private FaultSource {
 public:
  enum class State : std::uint8_t { kUnconfigured, kInactive, kActive };

  explicit Driver(std::unique_ptr<DriverInterface> driver);
  ~Driver();
  Driver(const Driver&) = delete;
  Driver& operator=(const Driver&) = delete;

  /// Unconfigured or inactive -> inactive (unconfigured on failure). Refused while active, and
  /// for a rate <= 0 or above the driver's max_rate_hz.
  Result configure(const nlohmann::json& params, double rate_hz);
  /// Inactive -> active; success without effect when already active.
  Result activate();
  /// Active -> inactive (the driver drives the safe output); success when not active.
  Result deactivate();

  /// Commands the output [V]; kFault while not active.
  DriverStatus write(double output_v) noexcept;
  /// This tick's measurement: fresh (kOk, age 0) or the last one with its age (kStale); on any
  /// other status `out` still holds the last value.
  DriverStatus read(Measurement& out) noexcept;
  /// Every axis at once (axes() values; see DriverInterface::write_axes/read_axes), as
  /// write()/read() for one: a stale tick repeats each axis's last value with its age.
  DriverStatus write_axes(std::span<const double> outputs_v) noexcept;
  DriverStatus read_axes(std::span<Measurement> out) noexcept;
  /// Axes the configured driver serves, [1, kMaxAxes] (1 before configure()).
  std::size_t axes() const noexcept { return axes_; }
  /// Success when the configured driver serves `wanted` axes (>= 1); otherwise the failure
  /// names both counts.
  Result serves(std::size_t wanted) const;
  /// Drives the safe output now, in any state (a no-op before configure()).
  DriverStatus safe_state() noexcept;
  void set_run_active(bool active) noexcept;

  State state() const noexcept { return state_.load(std::memory_order_acquire); }
  /// The driver's limits and ranges (DriverInfo), as of the last configure()/activate().
  double max_rate_hz() const noexcept { return info_.max_rate_hz; }
  double output_min_v() const noexcept { return info_.output_min_v; }
  double output_max_v() const noexcept { return info_.output_max_v; }
  double safe_output_v() const noexcept { return info_.safe_output_v; }
  double measurement_resolution_um() const noexcept { return info_.measurement_resolution_um; }
  std::string_view type() const noexcept { return driver_->type(); }
  /// The driver's, plus output_v, position_um, stale_reads and last_fault ("none" before any)
  /// (not real-time).
  nlohmann::json diagnostics() const;

  DriverInterface& interface() noexcept { return *driver_; }

 private:
  enum class Fault : int { kNone = 0, kStaleReads };
  std::string describe_fault(int cause, std::int64_t detail) const override;
  /// A kFault from the driver: on_error() once per fault.
  DriverStatus faulted(DriverStatus s) noexcept;
  /// A read's outcome for `count` axes: fresh values kept, or the last ones with their age.
  DriverStatus finish_read(DriverStatus s, std::span<const Measurement> fresh,
                           std::span<Measurement> out) noexcept;
  Result refuse_rate(const char* when) const;
  /// A lifecycle hook's Result; an exception it throws becomes a failure naming the driver.
  template <typename Hook>
  Result guarded(Hook&& hook) const;

  FaultLog faults_;  // before driver_: its threads may report until it is destroyed
  std::unique_ptr<DriverInterface> driver_;
  std::atomic<State> state_{State::kUnconfigured};
  DriverInfo info_;
  double rate_hz_ = 0.0;
  std::size_t axes_ = 1;

  // Loop-thread state.
  bool in_fault_ = false;
  std::array<double, kMaxAxes> last_y_{};  // per axis
  std::uint64_t age_ = 0;
  std::uint64_t response_ticks_ = 0;

  // Written by the loop thread, read by diagnostics().
  std::atomic<double> output_v_{0.0};
  std::atomic<double> position_um_{0.0};
  std::atomic<std::uint64_t> stale_reads_{0};
};

}  // namespace hystbench::drivers
