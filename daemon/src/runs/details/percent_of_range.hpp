#pragma once
// A run's error figures as a share of a span: 100 x value / range [%], 0 where the range is not
// positive (a run that did not move). Real-time safe.
namespace hystbench::daemon::details {

inline double percent_of_range(double value, double range) noexcept {
  return range > 0.0 ? 100.0 * value / range : 0.0;
}

}  // namespace hystbench::daemon::details
