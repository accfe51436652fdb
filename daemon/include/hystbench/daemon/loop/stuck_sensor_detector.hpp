#pragma once
// Detects a sensor that repeats one value bit for bit although the output has moved enough that
// a live sensor must have changed: a frozen ADC, a converter that lost its clock, a link that
// replays its last frame as fresh.
//
// The rule. Let u_c be the output when the reading last changed. The output has "moved" once
// |u - u_c| >= span, where span = max(output_span_v, 2 counts / gain): a change smaller than one
// sensor count (resolution_um) cannot be seen, and right after a reversal a hysteretic actuator
// moves at about half its average gain (gain_um_per_v), hence two counts. From the first fresh
// tick at which the output has moved, the reading must still stay identical for `ticks` more
// ticks plus the response latency (latency_ticks: the model's identified delay and any fixed
// transport delay, plus the fresh reading's own response_ticks: how many ticks before it the
// output it answers was written, e.g. a thread-mode Modbus exchange) before it is stuck. Only a
// fresh reading can be found stuck; ticks without one (stale) count time and output movement.
// So a noise-free sensor that reads the same value during a hold is not faulted by the step
// after the hold, nor is a slow device whose answer comes after the window; a frozen one is
// found within the time the output needs to move the span, plus `ticks`, plus the latency
// (plus the wait for the next fresh reading).
//
// Real-time safe: O(1), no allocation, no exceptions.
#include <cstdint>

namespace hystbench::daemon {

struct StuckSensorOptions {
  /// Ticks the value must stay identical after the output has moved; 0 = off.
  std::uint64_t ticks = 0;
  /// Output movement [V] that a live sensor must show; > 0.
  double output_span_v = 1.0;
  /// One sensor count [µm]; 0 = unknown (the span alone decides).
  double resolution_um = 0.0;
  /// Average actuator gain [µm/V] (range / output range); 0 = unknown.
  double gain_um_per_v = 0.0;
  /// Response latency known in advance [ticks] (identified model delay, transport delay).
  std::uint64_t latency_ticks = 0;
};

class StuckSensorDetector {
 public:
  explicit StuckSensorDetector(StuckSensorOptions options = {}) noexcept;

  /// Forgets the history (call at the start of each run) and sets the run's known latency
  /// [ticks] (the active model's delay).
  void reset(std::uint64_t latency_ticks) noexcept;
  void reset() noexcept { reset(options_.latency_ticks); }

  /// Feeds the tick's fresh reading y [µm] with the output u [V] written in the same tick;
  /// response_ticks = ticks between the write that y answers and this tick. Returns true once
  /// y is stuck by the rule above. Stale readings (a driver reusing its value) must not be fed.
  bool update(double u, double y, std::uint64_t response_ticks = 0) noexcept;
  /// A tick without a fresh reading, with the output u [V] written in it: counts time and
  /// movement, never reports.
  void stale(double u) noexcept;

  /// The output movement [V] that must show in the reading (span and resolution combined).
  double effective_span_v() const noexcept { return span_v_; }
  const StuckSensorOptions& options() const noexcept { return options_; }

 private:
  void advance(double u) noexcept;

  StuckSensorOptions options_;
  double span_v_ = 1.0;
  std::uint64_t latency_ticks_ = 0;
  bool have_ = false;
  bool moved_ = false;
  double y_ = 0.0;
  double u_changed_ = 0.0;
  std::uint64_t since_moved_ = 0;
};

}  // namespace hystbench::daemon
