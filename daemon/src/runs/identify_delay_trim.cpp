// identify's delay trim: the extension's delay and mode are timed on the record's steps, where
// the one mode the model has stands also for the sensor's lag and the modes above it; what a
// fast sine needs is the delay that matches the plant's phase at that sine. The extension's
// fast sine measures its output's lag behind the reference (its fundamental's phase error, to a
// fraction of a sample); the model with that lag added to its delay plays the same sine, and
// the extension takes the trimmed delay when it tracks the sine better. The middle sine then
// plays the model kept (Bench members on the supervisor thread; identify_session.hpp).
#include <cmath>
#include <string>

#include "runs/details/identify_session.hpp"

namespace hystbench::daemon {

using nlohmann::json;

namespace {

// A lag below this is no trim [samples]: at a twentieth of the loop rate it is 0.2 degrees, a
// few thousandths of the sine's amplitude.
constexpr double kMinTrimSamples = 0.01;
// A lag above this is not a trim of a timed delay but a timing that failed [samples].
constexpr double kMaxTrimSamples = 1.0;
// The trimmed delay is kept when the fast sine's rms falls by more than the spread between two
// runs of one model.
constexpr double kTrimGain = 0.97;

}  // namespace

void Bench::queue_delay_trim() {
  IdentifySession& s = *session_;
  if (!s.extended || !s.trim_delay || s.trim_tried || s.interrupted) return;
  const IdentifyCandidate& ext = s.candidates[*s.extended];
  const auto fast = ext.sines.find(s.fast_hz);
  if (fast == ext.sines.end()) return;  // not played yet
  s.trim_tried = true;
  const double lag = fast->second.value("lag_samples", 0.0);
  const double delay = ext.fit.model.delay_s() / dt_;  // [samples]
  json trim = {{"sine_hz", s.fast_hz}, {"lag_samples", lag}, {"delay_samples", delay}};
  if (!std::isfinite(verified_sine_rms(ext, s.fast_hz)) || !std::isfinite(lag)) {
    trim["kept"] = false;
    trim["why"] = "the fast sine did not run to the end";
  } else if (std::abs(lag) < kMinTrimSamples) {
    trim["kept"] = false;
    trim["why"] = "the fast sine's lag is within 0.01 samples";
  } else if (std::abs(lag) > kMaxTrimSamples || delay + lag < 0.0) {
    trim["kept"] = false;
    trim["why"] = "the fast sine's lag is more than a sample: the timing, not a trim";
  } else {
    IdentifyCandidate trial{ext.fit, json(), ext.label + "-trimmed", {}};
    trial.fit.model.set_delay((delay + lag) * dt_);
    trial.fit.model.configure(dt_);
    s.candidates.push_back(std::move(trial));
    s.trim = s.candidates.size() - 1;
    s.jobs.insert(s.jobs.begin() + static_cast<std::ptrdiff_t>(s.next), {*s.trim, s.fast_hz});
  }
  s.extension["delay_trim"] = std::move(trim);
}

void Bench::settle_delay_trim() {
  if (!session_ || !session_->trim) return;
  IdentifySession& s = *session_;
  IdentifyCandidate& trial = s.candidates[*s.trim];
  if (!s.interrupted && !trial.sines.contains(s.fast_hz)) return;  // still to play
  IdentifyCandidate& ext = s.candidates[*s.extended];
  const double before = verified_sine_rms(ext, s.fast_hz);
  const double after = verified_sine_rms(trial, s.fast_hz);
  json& trim = s.extension["delay_trim"];
  const bool kept = std::isfinite(after) && after <= kTrimGain * before;
  trim["fast_rms_percent"] = {{"timed", before},
                              {"trimmed", std::isfinite(after) ? json(after) : json()}};
  trim["kept"] = kept;
  trim["why"] = kept ? "the trimmed delay tracks the fast sine better"
                     : "the trimmed delay does not track the fast sine 3 % better";
  if (kept) {
    const double samples = trial.fit.model.delay_s() / dt_;
    ext.fit.model = std::move(trial.fit.model);
    ext.fit.delay_samples = static_cast<int>(std::lround(samples));
    ext.fit.notes.push_back("delay trimmed on the bench's " + std::to_string(s.fast_hz) +
                            " Hz sine to " + std::to_string(samples) + " samples");
    ext.sines[s.fast_hz] = std::move(trial.sines[s.fast_hz]);
  }
  s.candidates.pop_back();
  s.trim.reset();
}

}  // namespace hystbench::daemon
