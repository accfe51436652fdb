#pragma once
// Detects a sensor that repeats one value bit for bit while the output sweeps a span: a frozen
// ADC, a converter that lost its clock, a link that replays its last frame as fresh. A real
// displacement sensor's reading changes (noise, at least one code) once the output has moved a
// few percent of its range. Real-time safe: O(1), no allocation, no exceptions.
#include <cstdint>

namespace hystbench::daemon {

struct StuckSensorOptions {
  /// Fresh readings that must repeat the same value before it counts as stuck; 0 = off.
  std::uint64_t ticks = 0;
  /// Output span [V] that must be swept while the reading repeats; > 0.
  double output_span_v = 1.0;
};

class StuckSensorDetector {
 public:
  explicit StuckSensorDetector(StuckSensorOptions options = {}) noexcept : options_(options) {}

  /// Forgets the history (call at the start of each run).
  void reset() noexcept { have_ = false; }

  /// Feeds one fresh reading y with the output u [V] written in the same tick. Returns true
  /// once y has stayed identical for options.ticks readings while u spanned output_span_v.
  /// Stale readings (a driver reusing its latest value) must not be fed.
  bool update(double u, double y) noexcept;

  const StuckSensorOptions& options() const noexcept { return options_; }

 private:
  StuckSensorOptions options_;
  bool have_ = false;
  double y_ = 0.0;
  double u_lo_ = 0.0;
  double u_hi_ = 0.0;
  std::uint64_t repeats_ = 0;
};

}  // namespace hystbench::daemon
