#pragma once
// How much later than usual a reading came, for the feedback of one axis. A driver that exchanges
// on its own thread (Modbus with io = "thread", a CAN amplifier) sometimes stalls: a run of stale
// ticks, during which the stage gets no new output, then a reading that may answer an older output
// than usual. The feedback must not correct what the stall alone made:
//
// - Late: a fresh reading's response_ticks above the run's usual (the most frequent so far: the
//   driver's latency, which the feedforward's delay and the loop's design already hold). Old
//   sample or new one of a stage whose output came late, it shows what the stage did with the
//   output it answers; the feedback compares it with the reference of `late` ticks before
//   (DriveInput::y_late_ticks), not with this tick's, which has moved on since. A quicker answer
//   than the usual is not early, and one of them does not move the usual: compared with the
//   reference a tick before, every usual reading would show a tick's motion as an error.
// - Stalled: the gap since the last fresh reading longer than the run's usual gap (most
//   frequent) by two ticks or more. The stage, without new outputs while it lasted, lags behind
//   its reference; the next outputs bring it back by themselves, and a correction added to theirs
//   overshoots. The feedback holds over as many fresh readings as the stall added ticks. A device
//   that answers every second or third tick as a rule never stalls by that rule.
//
// The run's error figures score every tick as read: the sample's time is not known, and a stage
// whose outputs stalled did lag. A driver that always answers alike (the loopback, io = "loop")
// is never late nor stalled.
//
// Loop thread only; noexcept, allocation-free and lock-free.
#include <array>
#include <cstdint>

namespace hystbench::daemon {

class ReadingLateness {
 public:
  /// Responses and gaps counted; a larger one counts as this one less one.
  static constexpr std::uint64_t kCounted = 64;

  /// What a fresh reading tells the feedback.
  struct Fresh {
    std::uint64_t late_ticks = 0;  ///< compare it with the reference of this many ticks before
    bool hold = false;             ///< it follows a stall: the feedback holds
  };

  /// A new run: no reading seen.
  void reset() noexcept;
  /// A stale tick: the gap to the next fresh reading grows.
  void stale() noexcept { ++stale_run_; }
  /// A fresh reading that answers the output of `response_ticks` ago (the usual response and
  /// gap are the most frequent of the run's fresh readings so far, this one counted; the smaller
  /// on a tie).
  Fresh fresh(std::uint64_t response_ticks) noexcept;

 private:
  using Counts = std::array<std::uint32_t, kCounted>;
  /// Counts `value` in `counts` and moves `usual` to it where it is now the most frequent.
  static void count(Counts& counts, std::uint64_t& usual, std::uint64_t value) noexcept;
  Counts responses_{}, gaps_{};
  std::uint64_t usual_response_ = 0, usual_gap_ = 1;
  std::uint64_t stale_run_ = 0;  ///< stale ticks since the last fresh reading
  std::uint64_t holding_ = 0;    ///< fresh readings still held after a stall
};

}  // namespace hystbench::daemon
