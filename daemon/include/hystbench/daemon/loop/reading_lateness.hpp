#pragma once
// How much later than usual a reading answered, for the feedback of one axis. A driver that
// exchanges on its own thread (Modbus with io = "thread", a CAN amplifier) sometimes answers late:
// its reading answers the output of response_ticks ago, more than its usual latency, after a
// run of stale ticks. Whether the value is an old sample delivered late or a new one of a stage
// whose command arrived late, it shows what the stage did with the output it answers; against
// this tick's reference it shows the reference's motion since then as an error, which the
// feedback would correct, and overshoot once the exchange catches up. The feedback compares it
// with the reference of `late` ticks before instead (DriveInput::y_late_ticks). The run's error
// figures score every tick as read, unchanged: the sample's time is not known.
//
// Late: how far response_ticks exceed the run's usual, the most frequent so far (the driver's
// latency, which the feedforward's delay and the loop's design already hold). A quicker answer
// than the usual is not early, and one of them does not move the usual: compared with the
// reference a tick before, every usual reading would show a tick's motion as an error. A driver
// that always answers alike (the loopback, io = "loop") is never late.
//
// Loop thread only; noexcept, allocation-free and lock-free.
#include <array>
#include <cstdint>

namespace hystbench::daemon {

class ReadingLateness {
 public:
  /// Responses counted; a larger one counts as this one less one.
  static constexpr std::uint64_t kResponses = 64;

  /// A new run: no reading seen.
  void reset() noexcept;
  /// A fresh reading that answers the output of `response_ticks` ago: how many ticks later it is
  /// than the run's usual (>= 0; the most frequent response_ticks of the run's fresh readings so
  /// far, this one counted; the smaller one on a tie).
  std::uint64_t late_ticks(std::uint64_t response_ticks) noexcept;

 private:
  std::array<std::uint32_t, kResponses> responses_{};  ///< fresh readings by response_ticks
  std::uint64_t usual_ = 0;
};

}  // namespace hystbench::daemon
