#include "runs/details/track_learning.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "hystbench/compensation/number_text.hpp"

namespace hystbench::daemon::details {

namespace hc = compensation;
using nlohmann::json;

LearnedFor learned_for(const LearningRequest& r, std::size_t period_samples) {
  return {r.reference, period_samples, r.frequency_hz, r.rate_hz, r.min_um, r.max_um, r.signature};
}

TrackLearning::TrackLearning(const hc::ActuatorModel& model, LearningExchange& exchange,
                             LearningRequest request, const hc::LearningOptions& options)
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

namespace {

// x less its least-squares straight line over [from, size).
void remove_line(std::vector<double>& x, std::size_t from) {
  const auto n = static_cast<double>(x.size() - from);
  double st = 0.0, sx = 0.0, stt = 0.0, stx = 0.0;
  for (std::size_t j = from; j < x.size(); ++j) {
    const auto t = static_cast<double>(j - from);
    st += t, sx += x[j], stt += t * t, stx += t * x[j];
  }
  const double den = n * stt - st * st;
  const double slope = den > 0.0 ? (n * stx - st * sx) / den : 0.0;
  const double offset = (sx - slope * st) / n;
  for (std::size_t j = from; j < x.size(); ++j)
    x[j] -= offset + slope * static_cast<double>(j - from);
}

// x less its first `harmonics` harmonics over [from, size) (least squares: the window's own
// Fourier series, orthogonal to a constant and to each other there).
void remove_harmonics(std::vector<double>& x, std::size_t from, std::size_t harmonics) {
  const std::size_t n = x.size() - from;
  for (std::size_t h = 1; h <= harmonics; ++h) {
    const double w = 2.0 * std::numbers::pi * static_cast<double>(h) / static_cast<double>(n);
    double c = 0.0, s = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
      c += x[from + j] * std::cos(w * static_cast<double>(j));
      s += x[from + j] * std::sin(w * static_cast<double>(j));
    }
    c *= 2.0 / static_cast<double>(n);
    s *= 2.0 / static_cast<double>(n);
    for (std::size_t j = 0; j < n; ++j) {
      x[from + j] -=
          c * std::cos(w * static_cast<double>(j)) + s * std::sin(w * static_cast<double>(j));
    }
  }
}

}  // namespace

double TrackLearning::scored_rms(const std::vector<double>& e) const noexcept {
  const std::size_t from = std::min(request_.scored_from, e.size() - 1);
  double sum2 = 0.0;
  for (std::size_t j = from; j < e.size(); ++j) sum2 += e[j] * e[j];
  return std::sqrt(sum2 / static_cast<double>(e.size() - from));
}

TrackLearning::Trial TrackLearning::score(std::uint64_t number, std::uint64_t first_tick) const {
  const std::size_t from = std::min(request_.scored_from, e_.size() - 1);
  const std::size_t n = e_.size() - from;
  double sum2 = 0.0, peak = 0.0;
  std::size_t peak_at = from;
  for (std::size_t j = from; j < e_.size(); ++j) {
    sum2 += e_[j] * e_[j];
    if (std::abs(e_[j]) > peak) {
      peak = std::abs(e_[j]);
      peak_at = j;
    }
  }
  Trial t;
  t.trial = number;
  t.max_tick = first_tick + peak_at;
  t.rms_um = std::sqrt(sum2 / static_cast<double>(n));
  t.max_um = peak;
  t.rms_percent = percent(t.rms_um);
  t.max_percent = percent(peak);
  t.gain = number == 0 ? 0.0 : next_gain_;
  t.drive = number != 0 ? next_drive_ : request_.start_drive.empty() ? "compensator" : "saved";
  return t;
}

void TrackLearning::measure_floor() {
  // What differs between the two plays of one drive, less a straight line over the trial: what
  // the start from rest still moves slowly (creep, a switching front's tail) is not what does
  // not repeat. Over a trial of kFloorMinSamples or more, less its first kFloorSettlingHarmonics
  // harmonics too: the loop still settling toward the orbit it repeats shows there, at the
  // trial's fundamental and second harmonic, and the rms is scaled back for the share of a
  // noise that takes (2 h of the n samples' degrees of freedom). Over a shorter trial those
  // harmonics are much of the band, and are kept.
  std::vector<double> d(e_.size());
  for (std::size_t j = 0; j < d.size(); ++j) d[j] = e_[j] - first_error_[j];
  const std::size_t from = std::min(request_.scored_from, d.size() - 1);
  remove_line(d, from);
  const std::size_t n = d.size() - from;
  double noise_share = 1.0;
  if (n >= kFloorMinSamples) {
    remove_harmonics(d, from, kFloorSettlingHarmonics);
    noise_share = static_cast<double>(n) / static_cast<double>(n - 2 * kFloorSettlingHarmonics);
  }
  floor_um_ = scored_rms(d) * std::sqrt(noise_share) / std::sqrt(2.0);
  if (first_floor_um_ == 0.0) first_floor_um_ = floor_um_;
}

bool TrackLearning::stop_on_best(const Trial& t, bool at_floor) {
  // The best drive plays twice: the first period settles the actuator after the trials that
  // went wrong (their extremes and creep), the second is the run's last trial. Where the trials
  // asked for leave one more, it plays once: the run never plays more trials than asked.
  // Where the trial just taken repeated the best drive to measure the floor, it settled the
  // actuator already: the drive plays once more.
  const bool used_up = t.trial >= request_.trials;
  const bool settled = t.drive == "repeat" && u_ == best_drive_;
  const bool last = stopped_ || used_up || settled;
  const std::string plays = used_up   ? "once, as the last of the trials asked for"
                            : settled ? "once more (its repeat settled the actuator)"
                                      : "twice (the first settles the actuator)";
  // The trial that reached the floor: this one where it is within kFloorReach of it, else the
  // one its repeat measured the floor after (the floor held there).
  const bool after_repeat = remeasured() && t.trial == floor_trials_[1] &&
                            t.rms_um > kFloorReach * floor_um_ && trials_.size() >= 2;
  const Trial& reached = after_repeat ? trials_[trials_.size() - 2] : t;
  if (!stopped_) {
    why_ = at_floor
               ? "trial " + std::to_string(reached.trial) + " reached the bench's floor (" +
                     hc::significant(reached.rms_um / floor_um_, 3) +
                     "x the part of the error that does not repeat, measured on trials " +
                     std::to_string(floor_trials_[0]) + " and " + std::to_string(floor_trials_[1]) +
                     ", the same drive): learning on would learn what does not "
                     "repeat; the best trial's drive plays " +
                     plays
               : "two trials in a row more than 20 % above the best (trial " +
                     std::to_string(trials_[guard_.best_trial() + 1].trial) +
                     "): the learning stopped and plays the best trial's drive " + plays;
  }
  stopped_ = true;
  next_ = best_drive_;
  next_gain_ = 0.0;
  next_drive_ = "best";
  return last;
}

void TrackLearning::offer_repeat(std::uint64_t number) {
  first_error_ = e_;
  next_ = u_;
  next_gain_ = 0.0;
  next_drive_ = "repeat";
  kept_ = next_;
  if (!exchange_.offer(next_, false)) {
    fail("the loop had not taken the drive before trial " + std::to_string(number + 1));
  }
}

void TrackLearning::learn_next() {
  next_gain_ = guard_.gain();
  next_drive_ = "learned";
  const auto start = std::chrono::steady_clock::now();
  next_.resize(u_.size());
  learner_.update(u_, e_, guard_.gain(), next_);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  update_ms_sum_ += ms;
  update_ms_max_ = std::max(update_ms_max_, ms);
  ++updates_;
}

std::vector<TrackLearning::Trial> TrackLearning::poll() {
  std::vector<Trial> scored;
  std::uint64_t number = 0, first_tick = 0;
  while (exchange_.take_trial(u_, c_, e_, number, &first_tick)) {
    const Trial t = score(number, first_tick);
    trials_.push_back(t);
    scored.push_back(t);
    if (done_) continue;  // the last trial: nothing more to offer
    if (repeats(number)) {
      // Trial 1 plays this drive again: the bench's floor is what differs between the two.
      offer_repeat(number);
      continue;
    }
    if (number == floor_trials_[1] && first_error_.size() == e_.size()) measure_floor();
    bool last = false;
    const hc::LearningGuard::Action action =
        stopped_ ? hc::LearningGuard::Action::kStop : guard_.after_trial(t.rms_um);
    if (!stopped_ && guard_.best_trial() == guard_.trials() - 1) {
      best_drive_ = u_;
      best_drive_trial_ = number;
    }
    // The repeat's floor within kFloorReach of the first: the first held, and the learning
    // reached it (the trial before did; the repeat's own error holds what drifted since).
    const bool confirmed =
        remeasured() && number == floor_trials_[1] && kFloorReach * floor_um_ >= first_floor_um_;
    const bool at_floor = !stopped_ && number >= 2 && floor_um_ > 0.0 &&
                          (t.rms_um <= kFloorReach * floor_um_ || confirmed);
    if (at_floor && !remeasured() && number + 2 <= request_.trials &&
        action != hc::LearningGuard::Action::kStop) {
      // The floor measured on trials 0 and 1 holds what did not repeat at their error, which
      // the start's settling and a nonlinear stage's slower orbit scale: the drive that reached
      // it plays again, and the pair measures the floor at the error the learning reached.
      // Learning goes on where the trial is above it.
      floor_trials_ = {number, number + 1};
      offer_repeat(number);
      continue;
    }
    if (action == hc::LearningGuard::Action::kStop || at_floor) {
      last = stop_on_best(t, at_floor);
    } else {
      learn_next();
      last = number >= request_.trials;  // trials 0 and 1 (its repeat), then N learned
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
                   "learned at, and the error's mean within the last trial's rms"
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

void TrackLearning::put_last_trial_figures(json& figures) const {
  const std::optional<Trial> last = last_trial();
  if (!last) return;
  figures["rms_error_um"] = last->rms_um;
  figures["max_error_um"] = last->max_um;
  figures["rms_error_percent"] = last->rms_percent;
  figures["max_error_percent"] = last->max_percent;
  figures["max_error_index"] = last->max_tick;
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

json TrackLearning::best_replayed() const {
  const Trial* best = nullptr;
  json replays = json::array();
  double worst = 0.0;
  for (const Trial& t : trials_) {
    if (t.drive == "best") {
      replays.push_back(t.rms_percent);
      worst = std::max(worst, t.rms_um);
    } else if (t.trial == best_drive_trial_) {
      best = &t;
    }
  }
  if (best == nullptr || replays.empty()) return nullptr;
  const bool held = worst <= kReplayHeld * best->rms_um;
  json r = {{"trial", best->trial},
            {"rms_error_percent", best->rms_percent},
            {"replays_rms_percent", std::move(replays)},
            {"held", held}};
  if (!held) {
    r["meaning"] = "its drive, played again, tracked " + hc::significant(worst / best->rms_um, 3) +
                   "x its own error: this bench does not repeat a drive as closely as the "
                   "floor's two trials showed (an exchange that stalls, a DAQ's own clock), and "
                   "the best trial was partly chance";
  }
  return r;
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
  json out = {
      {"trials", trials},
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
              : trials_.size() >= request_.trials + (request_.trials > 0 ? 2 : 1)
                  ? "every trial asked for was played"
                  : "the run ended before the trials asked for were played"},
      {"floor", floor_um_ > 0.0
                    ? json{{"rms_error_um", floor_um_},
                           {"rms_error_percent", percent(floor_um_)},
                           {"trials", floor_trials_},
                           {"first_rms_error_um", first_floor_um_},
                           {"first_rms_error_percent", percent(first_floor_um_)},
                           {"measured_on",
                            "two trials of the same drive (0 and 1, again where a trial reached "
                            "the floor they measured); the rms of their errors' "
                            "difference over sqrt(2), less its straight line (and over " +
                                std::to_string(kFloorMinSamples) + " samples or more its first " +
                                std::to_string(kFloorSettlingHarmonics) +
                                " harmonics: the start still settling)"},
                           {"reached", stopped_ && why_.find("floor") != std::string::npos}}
                    : json(nullptr)},
      {"measured_plant", learner_.uses_measured_plant()
                             ? json{{"harmonics", learner_.measured_harmonics()},
                                    {"left_out", learner_.measured_harmonics_left_out()},
                                    {"delay_added_ticks", learner_.residual_delay_samples()}}
                             : json(nullptr)},
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
  // Only where the learning stopped and replayed its best drive.
  if (json replayed = best_replayed(); !replayed.is_null()) {
    out["best_replayed"] = std::move(replayed);
  }
  return out;
}

}  // namespace hystbench::daemon::details
