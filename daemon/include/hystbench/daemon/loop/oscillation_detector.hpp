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
// Real-time safe: O(1), no allocation, no exceptions.
#include <cstdint>

namespace hystbench::daemon {

struct OscillationOptions {
  double rate_hz = 10000.0;      ///< the loop's rate, > 0
  double frequency_hz = 1000.0;  ///< the band's centre, in (0, rate / 2)
  double span_um = 1.0;          ///< the reference's span, > 0
  double noise_rms_um = 0.0;     ///< the sensor's noise, >= 0
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
  /// Out-of-range options are clamped into range (the detector never throws).
  explicit OscillationDetector(OscillationOptions o) noexcept;

  /// Feeds the error of run tick k [µm] (NaN: skipped); true once it trips (then stays true).
  bool update(double error_um, std::uint64_t k) noexcept;
  const OscillationTrip& trip() const noexcept { return trip_; }
  const OscillationOptions& options() const noexcept { return o_; }

 private:
  OscillationOptions o_;
  double b0_ = 0.0, b2_ = 0.0, a1_ = 0.0, a2_ = 0.0;  // band-pass, b1 = 0
  double x1_ = 0.0, x2_ = 0.0, y1_ = 0.0, y2_ = 0.0;
  std::uint64_t window_ = 16, in_window_ = 0;
  double sum2_ = 0.0, last_rms_ = 0.0, floor_ = 0.0, sustained_level_ = 0.0;
  int growing_ = 0, sustained_ = 0, sustained_needed_ = 5;
  OscillationTrip trip_;
};

}  // namespace hystbench::daemon
