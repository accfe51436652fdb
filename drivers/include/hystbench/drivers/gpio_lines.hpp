#pragma once
// Optional GPIO lines of the bench (libgpiod v1), on any driver:
//   enable      output: the amplifier enable, on only while a run is active; one line for
//               every axis, or one per axis of a stage (an amplifier channel each)
//   estop       input: the emergency stop; asserted = safe output within the tick and FAULT
//   run_active  output: on while a run is active (for scopes)
//   sync_pulse  output: a pulse of sync_pulse_ticks at the start of each run, and every
//               sync_every_ticks ticks during it (0 = start only), to trigger a scope
// Config, the `gpio` table inside the driver's table ([driver.modbus.gpio], [driver.can.gpio]):
//   chip = "gpiochip0"            default chip for every line: name, number, path or label
//   consumer = "hystbench"        the consumer label shown by gpioinfo
//   sync_pulse_ticks = 1, sync_every_ticks = 0
//   [gpio.enable] [gpio.estop] [gpio.run_active] [gpio.sync_pulse]
//       line = "AMP_EN" | 17      line name or offset;  chip = ... (overrides);
//       active_low = false        (estop defaults to true: a pulled-up, normally-closed switch)
//   enable = [{line = "X_EN"}, {line = "Y_EN"}]   a stage: one table per axis, in axis order
//                                 (GpioDriver refuses a count other than 1 or the axes)
// Values below are logical (true = asserted); active_low maps them to the pin level.
// The line backend is abstract so tests own the lines (MemoryGpioBackend); set()/get() are
// real-time safe (libgpiod: one ioctl).
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hystbench::drivers {

class GpioLine {
 public:
  virtual ~GpioLine() = default;
  /// Drives an output to the logical value; false on failure.
  virtual bool set(bool asserted) noexcept = 0;
  /// Reads the logical value: 1 asserted, 0 not, -1 failure.
  virtual int get() noexcept = 0;
};

struct GpioLineConfig {
  std::string chip;  ///< name ("gpiochip0"), number ("0"), path or label
  std::string line;  ///< name, or offset as digits
  bool active_low = false;
  std::string describe() const { return chip + ":" + line; }
};

class GpioBackend {
 public:
  virtual ~GpioBackend() = default;
  /// Requests the line; throws std::runtime_error naming chip and line.
  virtual std::unique_ptr<GpioLine> request_output(const GpioLineConfig& c, bool initial,
                                                   const std::string& consumer) = 0;
  virtual std::unique_ptr<GpioLine> request_input(const GpioLineConfig& c,
                                                  const std::string& consumer) = 0;
};

/// libgpiod v1 (/dev/gpiochip*).
std::shared_ptr<GpioBackend> make_libgpiod_backend();

/// In-memory lines for tests: pin levels by "chip:line", read and written from any thread.
class MemoryGpioBackend final : public GpioBackend {
 public:
  std::unique_ptr<GpioLine> request_output(const GpioLineConfig& c, bool initial,
                                           const std::string& consumer) override;
  std::unique_ptr<GpioLine> request_input(const GpioLineConfig& c,
                                          const std::string& consumer) override;
  /// The pin level (after active_low) of "chip:line"; false when never driven.
  bool level(const std::string& chip_line) const;
  void set_level(const std::string& chip_line, bool high);
  /// Rising edges seen on an output.
  int rising_edges(const std::string& chip_line) const;
  /// Lines currently requested.
  int requested() const;

  struct Pin;

 private:
  std::shared_ptr<Pin> pin(const std::string& chip_line);
  mutable std::mutex m_;
  std::map<std::string, std::shared_ptr<Pin>> pins_;
};

struct GpioConfig {
  /// The enable lines: none, one for every axis, or one per axis (in axis order).
  std::vector<GpioLineConfig> enable;
  std::optional<GpioLineConfig> estop, run_active, sync_pulse;
  std::string consumer = "hystbench";
  std::uint32_t sync_pulse_ticks = 1;
  std::uint64_t sync_every_ticks = 0;
  bool any() const { return !enable.empty() || estop || run_active || sync_pulse; }
};

/// Parses the gpio table at `path` ("driver.modbus.gpio"); throws std::invalid_argument naming
/// the key.
GpioConfig parse_gpio_config(const nlohmann::json& table, const std::string& path);

/// The requested lines and their per-tick behaviour. request()/release() are not real-time;
/// the rest is, and is called from the loop thread only.
class GpioLines {
 public:
  /// Requests every configured line, outputs de-asserted. Throws naming the line.
  void request(const GpioConfig& config, GpioBackend& backend);
  void release() noexcept;
  /// A run starts (enable, run_active on, sync pulse) or ends (all off).
  void set_run_active(bool active) noexcept;
  /// Once per tick: the sync pulse.
  void tick() noexcept;
  /// True when the e-stop is asserted or cannot be read (fail safe).
  bool estop_asserted() noexcept;
  /// Enable, run_active and sync off.
  void safe() noexcept;
  bool run_active() const noexcept { return run_active_; }

 private:
  GpioConfig config_;
  std::vector<std::unique_ptr<GpioLine>> enable_;
  std::unique_ptr<GpioLine> estop_, run_active_line_, sync_;
  bool run_active_ = false;
  std::uint64_t run_ticks_ = 0;
  std::uint64_t pulse_off_at_ = 0;
};

}  // namespace hystbench::drivers
