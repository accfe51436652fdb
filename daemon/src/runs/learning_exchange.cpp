#include "hystbench/daemon/runs/learning_exchange.hpp"

#include <algorithm>
#include <cmath>

namespace hystbench::daemon {

LearningExchange::LearningExchange(std::size_t period_samples, std::uint64_t first,
                                   std::size_t lead_in)
    : period(period_samples),
      first_tick(first),
      lead_in_periods(std::max<std::size_t>(lead_in, 1)),
      lead_start_(first - std::min<std::uint64_t>(first, lead_in_periods * period_samples)),
      start_(first),
      min_periods_(lead_in_periods) {
  for (int i = 0; i < 2; ++i) {
    drive_[i].assign(period, 0.0);
    rec_u_[i].assign(period, 0.0);
    rec_c_[i].assign(period, 0.0);
    rec_e_[i].assign(period, 0.0);
  }
}

void LearningExchange::start_recording(std::uint64_t trial, std::uint64_t k) noexcept {
  const std::size_t s = trial % 2;
  rec_tick_ = k;
  int state = slot_[s].load(std::memory_order_acquire);
  // A full slot the learner never took is written over (it fell behind); one it is reading is
  // left alone and this trial goes unrecorded.
  while ((state == kFree || state == kFull) &&
         !slot_[s].compare_exchange_weak(state, kWriting, std::memory_order_acq_rel)) {
  }
  rec_slot_ = state == kFree || state == kFull ? static_cast<int>(s) : -1;
}

std::size_t LearningExchange::begin_tick(std::uint64_t k) noexcept {
  const std::uint64_t since = k - start_;
  const auto j = static_cast<std::size_t>(since % period);
  if (j != 0) return j;
  const int ready = ready_.exchange(-1, std::memory_order_acq_rel);
  if (since == 0) {
    playing_ = ready;  // the compensator's drive (-1), or one learned before
    playing_started_ = ready >= 0;
    last_ = ready >= 0 && ready_last_.load(std::memory_order_acquire);
    trial_ = 0;
    start_recording(0, k);
    return j;
  }
  if (ready < 0) {
    stale_.fetch_add(1, std::memory_order_acq_rel);
    rec_slot_ = -1;
    return j;
  }
  playing_ = ready;
  playing_started_ = false;
  last_ = ready_last_.load(std::memory_order_acquire);
  start_recording(++trial_, k);
  return j;
}

bool LearningExchange::learned(std::size_t j, double& u_ff, double twin) const noexcept {
  if (playing_ < 0) return false;
  const double moved = !playing_started_ || started_compensator_.empty() ? 0.0
                       : std::isfinite(twin)                             ? u_ff - twin
                                             : u_ff - started_compensator_[j];
  u_ff = drive_[static_cast<std::size_t>(playing_)][j] + moved;
  return true;
}

void LearningExchange::follow_offset(std::size_t min_periods,
                                     const LearningLeadIn& lead_in) noexcept {
  min_periods_ = std::clamp<std::size_t>(min_periods, 1, lead_in_periods);
  follow_ = lead_in;
}

bool LearningExchange::lead_in(std::uint64_t k, double& u_ff, double twin) const noexcept {
  if (started_from_ == 0 || k >= start_ || k < lead_start_) return false;
  // The drive start_from made ready: the learner writes the other buffer first.
  const auto j = static_cast<std::size_t>((k - lead_start_) % period);
  const double moved = started_compensator_.empty() ? 0.0
                       : std::isfinite(twin)        ? u_ff - twin
                                                    : u_ff - started_compensator_[j];
  u_ff = drive_[0][j] + moved;
  return true;
}

void LearningExchange::decide_lead_in(std::uint64_t k, std::uint64_t begun, double tare) noexcept {
  if (begun + 1 < min_periods_) return;  // the last period begins at the minimum's last
  const bool longer = follow_.follow_periods > 0 && std::isfinite(follow_.learned_offset) &&
                      follow_.tolerance > 0.0;
  if (std::isnan(checkpoint_gap_)) checkpoint_gap_ = gap(tare);
  LeadInEnd end = LeadInEnd::kLongest;
  if (!longer) {
    end = LeadInEnd::kMinimum;
  } else if (settled(tare)) {
    end = LeadInEnd::kOffsetReached;
  } else if (begun + 1 >= lead_in_periods) {
    end = LeadInEnd::kLongest;
  } else if (stalled_ && !within_) {  // within, the settling's own steps bound it
    end = LeadInEnd::kOffsetStalled;
  } else {
    return;
  }
  if (together_ == nullptr) {
    end_lead_in(k, begun, end);
    return;
  }
  // With the other axes: counted here, ended on the next tick if every axis would end here
  // (each axis's first tick of the period comes in turn within this tick). The longest lead-in
  // is every axis's at the same period, so the count is whole there at the latest.
  if (together_->tick != k) {
    together_->tick = k;
    together_->ending = 0;
  }
  ++together_->ending;
  pending_ = true;
  pending_tick_ = k;
  pending_end_ = end;
}

bool LearningExchange::settled(double tare) noexcept {
  if (!within_ && gap(tare) > follow_.tolerance) return false;
  within_ = true;
  if (!(follow_.settled > 0.0)) return true;
  return (steps_within_ > 0 && std::abs(last_step_error_) <= follow_.settled) ||
         steps_within_ >= follow_.settle_steps;
}

void LearningExchange::end_lead_in(std::uint64_t k, std::uint64_t begun, LeadInEnd end) noexcept {
  end_ = end;
  decided_ = true;
  start_ = k + period;
  // A single lead-in period's first half still leaves the rest the run started from; after
  // more, the last period is whole (its mean, not half of it, is the offset).
  window_ = begun > 0 ? period : period / 2;
}

void LearningExchange::lead_in_error(std::uint64_t k, double error, double tare) noexcept {
  if (started_from_ == 0 || k >= start_ || k < lead_start_) return;
  const std::uint64_t since = k - lead_start_;
  if (pending_ && k == pending_tick_ + 1) {
    pending_ = false;
    if (together_->tick == pending_tick_ && together_->ending >= together_->axes) {
      end_lead_in(pending_tick_, (pending_tick_ - lead_start_) / period, pending_end_);
      if (start_ - pending_tick_ <= window_) {  // the period's first tick, before it was decided
        lead_in_error_sum_ += pending_error_;
        ++lead_in_samples_;
      }
    }
  }
  if (!decided_ && since % period == 0) {
    decide_lead_in(k, since / period, tare);
    if (pending_) pending_error_ = error;
  }
  if (decided_) {
    if (start_ - k <= window_) {
      lead_in_error_sum_ += error;
      ++lead_in_samples_;
    }
    return;
  }
  // Following: each step's mean error moves the offset the target takes off, the first step
  // (the start from rest) left out; every stall_steps the gap must have closed by the tolerance.
  const std::uint64_t step = follow_.follow_periods * period;
  if (step == 0 || since < step) return;
  follow_sum_ += error;
  ++follow_samples_;
  if ((since + 1) % step != 0) return;
  last_step_error_ = follow_sum_ / static_cast<double>(follow_samples_);
  followed_ -= last_step_error_;
  if (within_) ++steps_within_;
  follow_sum_ = 0.0;
  follow_samples_ = 0;
  const std::size_t checked = std::max<std::size_t>(follow_.stall_steps, 1);
  if (++follow_steps_ % checked == 0) {
    // At the pace the gap closed since the last check, it would not reach the tolerance before
    // the longest lead-in: waiting on would not bring the drive back where it was learned.
    const double now = gap(tare);
    const double closed = checkpoint_gap_ - now;
    const double left = static_cast<double>(lead_in_periods * period - (since + 1)) /
                        static_cast<double>(checked * step);
    stalled_ = closed <= 0.0 || now - follow_.tolerance > closed * left;
    checkpoint_gap_ = now;
  }
}

bool LearningExchange::end_tick(std::size_t j, double u_ff, double u_compensator,
                                double error) noexcept {
  if (rec_slot_ >= 0) {
    const auto s = static_cast<std::size_t>(rec_slot_);
    rec_u_[s][j] = u_ff;
    rec_c_[s][j] = u_compensator;
    rec_e_[s][j] = error;
  }
  if (j + 1 < period) return false;
  if (rec_slot_ >= 0) {
    const auto s = static_cast<std::size_t>(rec_slot_);
    slot_trial_[s].store(trial_, std::memory_order_relaxed);
    slot_tick_[s].store(rec_tick_, std::memory_order_relaxed);
    slot_[s].store(kFull, std::memory_order_release);
    played_.fetch_add(1, std::memory_order_acq_rel);
    rec_slot_ = -1;
  }
  return last_;
}

bool LearningExchange::owed(std::uint64_t k) const noexcept {
  if (k < start_ + period || (k - start_) % period != 0) return false;
  return ready_.load(std::memory_order_acquire) < 0 &&
         !final_offered_.load(std::memory_order_acquire) &&
         offered_.load(std::memory_order_acquire) - started_from_ <
             played_.load(std::memory_order_acquire);
}

bool LearningExchange::take_trial(std::vector<double>& u, std::vector<double>& c,
                                  std::vector<double>& e, std::uint64_t& trial,
                                  std::uint64_t* first_tick) {
  int pick = -1;
  for (int s = 0; s < 2; ++s) {
    if (slot_[s].load(std::memory_order_acquire) != kFull) continue;
    if (pick < 0 || slot_trial_[s].load(std::memory_order_relaxed) <
                        slot_trial_[pick].load(std::memory_order_relaxed)) {
      pick = s;
    }
  }
  if (pick < 0) return false;
  int state = kFull;
  if (!slot_[pick].compare_exchange_strong(state, kReading, std::memory_order_acq_rel)) {
    return false;  // the loop took it back to write over
  }
  u.assign(rec_u_[pick].begin(), rec_u_[pick].end());
  c.assign(rec_c_[pick].begin(), rec_c_[pick].end());
  e.assign(rec_e_[pick].begin(), rec_e_[pick].end());
  trial = slot_trial_[pick].load(std::memory_order_relaxed);
  if (first_tick != nullptr) *first_tick = slot_tick_[pick].load(std::memory_order_relaxed);
  slot_[pick].store(kFree, std::memory_order_release);
  taken_.fetch_add(1, std::memory_order_acq_rel);
  return true;
}

bool LearningExchange::start_from(const std::vector<double>& drive,
                                  const std::vector<double>& compensator, bool last) {
  if (!compensator.empty() && compensator.size() != period) return false;
  if (offered_.load(std::memory_order_acquire) != 0 || !offer(drive, last)) return false;
  started_compensator_ = compensator;
  started_from_ = 1;
  return true;
}

bool LearningExchange::offer(const std::vector<double>& drive, bool last) noexcept {
  if (ready_.load(std::memory_order_acquire) >= 0 || drive.size() != period) return false;
  // The loop took the drive offered before and plays it from the other buffer.
  const auto idx = static_cast<int>(offered_.load(std::memory_order_acquire) % 2);
  std::copy(drive.begin(), drive.end(), drive_[static_cast<std::size_t>(idx)].begin());
  ready_last_.store(last, std::memory_order_release);
  // The drive is made ready before it is counted: owed() must not see it counted (or the final
  // one offered) while ready_ is still empty, or the loop would go on without waiting and play
  // a stale period. Counted after, the loop at most waits for the count.
  ready_.store(idx, std::memory_order_release);
  offered_.fetch_add(1, std::memory_order_acq_rel);
  if (last) final_offered_.store(true, std::memory_order_release);
  return true;
}

}  // namespace hystbench::daemon
