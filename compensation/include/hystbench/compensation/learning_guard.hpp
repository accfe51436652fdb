#pragma once
// What iterative learning does after each trial, from the trial's error: learn on at the present
// gain, halve it (a trial more than 20 % above the best so far), or stop and keep the best trial's
// drive (two such trials in a row). Pure; real-time safe.
#include <cstddef>

namespace hystbench::compensation {

class LearningGuard {
 public:
  enum class Action { kLearn, kHalveGain, kStop };
  /// gain: the learning gain to start with, (0, 1].
  explicit LearningGuard(double gain) noexcept : gain_(gain) {}

  /// The trial just measured, its error (rms, any unit >= 0); trials are numbered from 0.
  Action after_trial(double rms) noexcept {
    const std::size_t trial = trials_++;
    if (trial == 0 || rms < best_rms_) {
      best_rms_ = rms;
      best_trial_ = trial;
    }
    if (rms > kWorse * best_rms_) {
      if (++worse_in_a_row_ >= 2) return Action::kStop;
      gain_ *= 0.5;
      return Action::kHalveGain;
    }
    worse_in_a_row_ = 0;
    return Action::kLearn;
  }

  double gain() const noexcept { return gain_; }
  std::size_t best_trial() const noexcept { return best_trial_; }
  double best_rms() const noexcept { return best_rms_; }
  std::size_t trials() const noexcept { return trials_; }

  static constexpr double kWorse = 1.2;  ///< a trial this much above the best halves the gain

 private:
  double gain_;
  double best_rms_ = 0.0;
  std::size_t best_trial_ = 0;
  std::size_t trials_ = 0;
  int worse_in_a_row_ = 0;
};

}  // namespace hystbench::compensation
