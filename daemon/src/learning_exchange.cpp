#include "hystbench/daemon/learning_exchange.hpp"

#include <algorithm>

namespace hystbench::daemon {

LearningExchange::LearningExchange(std::size_t period_samples, std::uint64_t first)
    : period(period_samples), first_tick(first) {
  for (int i = 0; i < 2; ++i) {
    drive_[i].assign(period, 0.0);
    rec_u_[i].assign(period, 0.0);
    rec_e_[i].assign(period, 0.0);
  }
}

void LearningExchange::start_recording(std::uint64_t trial) noexcept {
  const std::size_t s = trial % 2;
  int state = slot_[s].load(std::memory_order_acquire);
  // A full slot the learner never took is written over (it fell behind); one it is reading is
  // left alone and this trial goes unrecorded.
  while ((state == kFree || state == kFull) &&
         !slot_[s].compare_exchange_weak(state, kWriting, std::memory_order_acq_rel)) {
  }
  rec_slot_ = state == kFree || state == kFull ? static_cast<int>(s) : -1;
}

std::size_t LearningExchange::begin_tick(std::uint64_t k) noexcept {
  const std::uint64_t since = k - first_tick;
  const auto j = static_cast<std::size_t>(since % period);
  if (j != 0) return j;
  if (since == 0) {
    playing_ = -1;
    trial_ = 0;
    start_recording(0);
    return j;
  }
  const int ready = ready_.exchange(-1, std::memory_order_acq_rel);
  if (ready < 0) {
    stale_.fetch_add(1, std::memory_order_acq_rel);
    rec_slot_ = -1;
    return j;
  }
  playing_ = ready;
  last_ = ready_last_.load(std::memory_order_acquire);
  start_recording(++trial_);
  return j;
}

bool LearningExchange::learned(std::size_t j, double& u_ff) const noexcept {
  if (playing_ < 0) return false;
  u_ff = drive_[static_cast<std::size_t>(playing_)][j];
  return true;
}

bool LearningExchange::end_tick(std::size_t j, double u_ff, double error) noexcept {
  if (rec_slot_ >= 0) {
    const auto s = static_cast<std::size_t>(rec_slot_);
    rec_u_[s][j] = u_ff;
    rec_e_[s][j] = error;
  }
  if (j + 1 < period) return false;
  if (rec_slot_ >= 0) {
    const auto s = static_cast<std::size_t>(rec_slot_);
    slot_trial_[s].store(trial_, std::memory_order_relaxed);
    slot_[s].store(kFull, std::memory_order_release);
    played_.fetch_add(1, std::memory_order_acq_rel);
    rec_slot_ = -1;
  }
  return last_;
}

bool LearningExchange::owed(std::uint64_t k) const noexcept {
  if (k < first_tick + period || (k - first_tick) % period != 0) return false;
  return ready_.load(std::memory_order_acquire) < 0 &&
         !final_offered_.load(std::memory_order_acquire) &&
         offered_.load(std::memory_order_acquire) < played_.load(std::memory_order_acquire);
}

bool LearningExchange::take_trial(std::vector<double>& u, std::vector<double>& e,
                                  std::uint64_t& trial) noexcept {
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
  e.assign(rec_e_[pick].begin(), rec_e_[pick].end());
  trial = slot_trial_[pick].load(std::memory_order_relaxed);
  slot_[pick].store(kFree, std::memory_order_release);
  taken_.fetch_add(1, std::memory_order_acq_rel);
  return true;
}

bool LearningExchange::offer(const std::vector<double>& drive, bool last) noexcept {
  if (ready_.load(std::memory_order_acquire) >= 0 || drive.size() != period) return false;
  // The loop took the drive offered before and plays it from the other buffer.
  const auto idx = static_cast<int>(offered_.load(std::memory_order_acquire) % 2);
  std::copy(drive.begin(), drive.end(), drive_[static_cast<std::size_t>(idx)].begin());
  ready_last_.store(last, std::memory_order_release);
  if (last) final_offered_.store(true, std::memory_order_release);
  offered_.fetch_add(1, std::memory_order_acq_rel);
  ready_.store(idx, std::memory_order_release);
  return true;
}

}  // namespace hystbench::daemon
