#include "runs/details/track_learning.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace hystbench::daemon::details {

namespace hc = compensation;
using nlohmann::json;

LearnedFor learned_for(const LearningRequest& r, std::size_t period_samples) {
  return {r.reference, period_samples, r.frequency_hz, r.rate_hz, r.min_um, r.max_um, r.signature};
}

TrackLearning::TrackLearning(const hc::ActuatorModel& model, LearningExchange& exchange,
                             LearningRequest request, hc::LearningOptions options)
    : exchange_(exchange),
      request_(std::move(request)),
      learner_(model, exchange.period, options),
      mode_in_model_(model.dynamics().has_value()),
      cutoff_by_hand_(options.cutoff_hz > 0.0),
      guard_(request_.gain) {
  if (request_.start_drive.empty()) return;
  if (!exchange.start_from(request_.start_drive, request_.start_compensator,
                           request_.trials == 0)) {
    throw std::invalid_argument("the drive '" + request_.start_name + "' holds " +
                                std::to_string(request_.start_drive.size()) + " samples (" +
                                std::to_string(request_.start_compensator.size()) +
                                " of the compensator's), a trial " +
                                std::to_string(exchange.period));
  }
  kept_ = request_.start_drive;
  done_ = request_.trials == 0;  // a replay: trial 0 is the last
}

std::vector<TrackLearning::Trial> TrackLearning::poll() {
  std::vector<Trial> scored;
  std::uint64_t number = 0;
  while (exchange_.take_trial(u_, c_, e_, number)) {
    const std::size_t from = std::min(request_.scored_from, e_.size() - 1);
    const std::size_t n = e_.size() - from;
    double sum2 = 0.0, peak = 0.0;
    for (std::size_t j = from; j < e_.size(); ++j) {
      sum2 += e_[j] * e_[j];
      peak = std::max(peak, std::abs(e_[j]));
    }
    Trial t;
    t.trial = number;
    t.rms_um = std::sqrt(sum2 / static_cast<double>(n));
    t.max_um = peak;
    const double range = request_.range_um;
    t.rms_percent = range > 0.0 ? 100.0 * t.rms_um / range : 0.0;
    t.max_percent = range > 0.0 ? 100.0 * peak / range : 0.0;
    t.gain = number == 0 ? 0.0 : next_gain_;
    t.drive = number != 0 ? next_drive_ : request_.start_drive.empty() ? "compensator" : "saved";
    trials_.push_back(t);
    scored.push_back(t);
    if (done_) continue;  // the last trial: nothing more to offer
    bool last = false;
    const hc::LearningGuard::Action action =
        stopped_ ? hc::LearningGuard::Action::kStop : guard_.after_trial(t.rms_um);
    if (!stopped_ && guard_.best_trial() == guard_.trials() - 1) best_drive_ = u_;
    if (action == hc::LearningGuard::Action::kStop) {
      // The best drive plays twice: the first period settles the actuator after the trials that
      // went wrong (their extremes and creep), the second is the run's last trial.
      last = stopped_;
      stopped_ = true;
      why_ = "two trials in a row more than 20 % above the best (trial " +
             std::to_string(trials_[guard_.best_trial()].trial) +
             "): the learning stopped and plays the best trial's drive, twice (the first "
             "settles the actuator)";
      next_ = best_drive_;
      next_gain_ = 0.0;
      next_drive_ = "best";
    } else {
      next_gain_ = guard_.gain();
      next_drive_ = "learned";
      const auto start = std::chrono::steady_clock::now();
      next_.resize(u_.size());
      learner_.update(u_, e_, guard_.gain(), next_);
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count();
      update_ms_sum_ += ms;
      update_ms_max_ = std::max(update_ms_max_, ms);
      ++updates_;
      last = number + 1 >= request_.trials;
    }
    kept_ = next_;
    done_ = last;
    // The loop took the drive before: it played the trial just taken.
    if (!exchange_.offer(next_, last)) {
      fail("the loop had not taken the drive before trial " + std::to_string(number));
    }
  }
  return scored;
}

namespace {

// Why a drive learned before began its scored period where it did.
std::string lead_in_end(const LearningExchange& x) {
  switch (x.lead_in_end()) {
    case LearningExchange::LeadInEnd::kMinimum:
      return "the shortest lead-in, the offset not followed (lead_in_max_s no longer than it, or "
             "the offset the drive was learned at or its last trial not saved with it)";
    case LearningExchange::LeadInEnd::kOffsetReached:
      return x.lead_in_followed() != 0.0
                 ? "the offset, followed, came within the tolerance of the one the drive was "
                   "learned at"
                 : "the offset is within the tolerance of the one the drive was learned at";
    case LearningExchange::LeadInEnd::kOffsetStalled:
      return "the offset, followed, would not come within the tolerance of the one the drive was "
             "learned at before the longest lead-in (lead_in_max_s)";
    case LearningExchange::LeadInEnd::kLongest:
      return "the longest lead-in (lead_in_max_s): the offset is still off the one the drive was "
             "learned at";
  }
  return "";
}

}  // namespace

void TrackLearning::fail(const std::string& why) {
  exchange_.give_up();
  done_ = true;
  stopped_ = true;
  why_ = "the learning failed (" + why + "): the last drive played on to the run's end";
}

std::optional<TrackLearning::Trial> TrackLearning::last_trial() const {
  if (trials_.empty()) return std::nullopt;
  return trials_.back();
}

json TrackLearning::above_cutoff() const {
  if (!learner_.fast_trial()) {
    return {{"updates", 0}, {"why", "none: Q reaches the trial's fifth harmonic and more"}};
  }
  if (cutoff_by_hand_) {
    return {{"updates", 0}, {"why", "none: Q's cut-off was set (learn_cutoff_hz)"}};
  }
  const auto mode = learner_.high_band_mode();
  if (!mode) {
    return {{"updates", 0},
            {"why", "none: no mode known (the model holds none and its identify timed none)"}};
  }
  return {{"updates", learner_.high_band_updates()},
          {"mode_hz", mode->natural_frequency_hz},
          {"damping_ratio", mode->damping_ratio},
          {"mode_from", mode_in_model_ ? "the model" : "the steps its identify timed"}};
}

json TrackLearning::result() const {
  const bool started = !request_.start_drive.empty();
  json trials = json::array();
  for (const Trial& t : trials_) {
    trials.push_back({{"trial", t.trial},
                      {"rms_error_percent", t.rms_percent},
                      {"max_error_percent", t.max_percent},
                      {"rms_error_um", t.rms_um},
                      {"max_error_um", t.max_um},
                      {"gain", t.gain},
                      {"drive", t.drive}});
  }
  // The best of every trial played (the guard does not score the last one).
  std::size_t best = 0;
  for (std::size_t i = 1; i < trials_.size(); ++i) {
    if (trials_[i].rms_um < trials_[best].rms_um) best = i;
  }
  return {{"trials", trials},
          {"trials_requested", request_.trials},
          {"gain", request_.gain},
          {"cutoff_hz", learner_.cutoff_hz()},
          {"above_cutoff", above_cutoff()},
          {"delay_ticks",
           {{"model", learner_.model_delay_samples()},
            {"used", learner_.delay_samples()},
            {"measurements", learner_.delay_measurements()}}},
          {"period_samples", exchange_.period},
          {"scored_from", request_.scored_from},
          {"reference", request_.reference},
          {"frequency_hz", request_.frequency_hz},
          {"stopped", stopped_},
          {"why", stopped_ ? why_
                  : trials_.size() >= request_.trials + 1
                      ? "every trial asked for was played"
                      : "the run ended before the trials asked for were played"},
          {"started_from", request_.start_name.empty() ? json() : json(request_.start_name)},
          {"lead_in_offset_um", exchange_.lead_in_offset()},
          {"lead_in_periods", started ? exchange_.lead_in_played() : 0},
          {"lead_in_followed_um", exchange_.lead_in_followed()},
          {"lead_in_end", started ? lead_in_end(exchange_) : "none: no drive learned before"},
          {"best_trial", trials_.empty() ? json() : json(trials_[best].trial)},
          {"stale_periods", exchange_.stale_periods()},
          {"update_ms",
           {{"mean", updates_ ? update_ms_sum_ / static_cast<double>(updates_) : 0.0},
            {"max", update_ms_max_},
            {"count", updates_}}}};
}

}  // namespace hystbench::daemon::details
