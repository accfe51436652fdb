#pragma once
// Detects a feedback loop that oscillates: the error, band-passed around the frequency where the
// loop is closest to instability (the designed loop's peak of |S|, where an unstable or marginal
// loop rings), measured as its rms over windows of eight periods of that frequency. It trips on
//   - a growing oscillation: the window rms above the floor and up by 40 % or more on each of
//     four windows in a row (x3.8 over 32 periods; a loop's transients decay, they never grow
//     window after window);
//   - a sustained one (a limit cycle, growth stopped by a clamp): the window rms above 5 % of
//     the reference's span for 20 ms or five windows, whichever is longer (a fast reference's
//     harmonics through a stable loop stay far below it).
// The floor is the larger of ten times the sensor's noise and 0.2 % of the span.
// Where the reference repeats, what the band watches is the error's change over one of its
// periods: a stable loop's answer to the reference is locked to it and cancels (a fast reference
// near the peak of |S| leaves an error of several % of the span there, period after period),
// while a loop's own oscillation is not locked to it and stays (within a factor
// 2 |sin(pi f P / rate)| of itself, f its frequency, P the period in ticks).
// update() is real-time safe: O(1), no allocation, no exceptions; the constructor allocates the
// period's buffer (off the loop).
#include <cstddef>
#include <cstdint>
#include <vector>

namespace hystbench::daemon {

struct OscillationOptions {
  double rate_hz = 10000.0;      ///< the loop's rate, > 0
  double frequency_hz = 1000.0;  ///< the band's centre, in (0, rate / 2)
  double span_um = 1.0;          ///< the reference's span, > 0
  double noise_rms_um = 0.0;     ///< the sensor's noise, >= 0
  /// The reference's period [ticks, fractional allowed] where it repeats; 0: it does not (or
  /// longer than kMaxPeriodTicks): the error itself is watched.
  double period_samples = 0.0;
};

/// What tripped, for the run's result.
struct OscillationTrip {
  bool tripped = false;
  bool growing = false;       ///< growing (true) or sustained (false)
  double rms_um = 0.0;        ///< the band's rms in the window that tripped
  double frequency_hz = 0.0;  ///< the band's centre
  std::uint64_t tick = 0;     ///< the run tick at which it tripped
};

class OscillationDetector {
 public:
  /// The longest reference period whose change is watched [ticks].
  static constexpr double kMaxPeriodTicks = 1 << 20;

  /// Out-of-range options are clamped into range (a period out of range: not periodic); throws
  /// only std::bad_alloc.
  explicit OscillationDetector(OscillationOptions o);

  /// Feeds the error of run tick k [µm] (NaN: skipped); true once it trips (then stays true).
  bool update(double error_um, std::uint64_t k) noexcept;
  const OscillationTrip& trip() const noexcept { return trip_; }
  const OscillationOptions& options() const noexcept { return o_; }

 private:
  // The error's change over one reference period (the error itself without one).
  double change_over_period(double e) noexcept;

  OscillationOptions o_;
  std::vector<double> history_;  // the last errors, a ring (empty: not periodic)
  std::size_t head_ = 0;         // where the next error goes
  std::uint64_t seen_ = 0;       // errors fed
  std::size_t whole_ = 0;        // the period's whole ticks and its fraction
  double frac_ = 0.0;
  double b0_ = 0.0, b2_ = 0.0, a1_ = 0.0, a2_ = 0.0;  // band-pass, b1 = 0
  double x1_ = 0.0, x2_ = 0.0, y1_ = 0.0, y2_ = 0.0;
  std::uint64_t window_ = 16, in_window_ = 0;
  double sum2_ = 0.0, last_rms_ = 0.0, floor_ = 0.0, sustained_level_ = 0.0;
  int growing_ = 0, sustained_ = 0, sustained_needed_ = 5;
  OscillationTrip trip_;
};

}  // namespace hystbench::daemon
