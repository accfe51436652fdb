// identify's delay trim: the extension's delay and mode are timed on the record's steps, where
// the one mode the model has stands also for the sensor's lag and the modes above it; what a
// fast sine needs is the delay that matches the plant's phase at that sine. The extension's
// fast sine measures its output's lag behind the reference (its fundamental's phase error, to a
// fraction of a sample); the model with that lag added to its delay and the model as timed play
// the same sine, and the extension takes the trimmed delay when it tracks the sine better. The
// middle sine then plays the model kept (the identify coordinator on the supervisor thread;
// identify_coordinator.hpp).
#include <cmath>
#include <string>

#include "hystbench/compensation/number_text.hpp"
#include "service/details/identify_coordinator.hpp"
#include "service/details/identify_session.hpp"

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

void details::IdentifyCoordinator::queue_delay_trim() {
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
    // The trimmed model, then the timed one again, each after the same short precondition
    // sweep (the daemon's would add a second to each 40 ms segment): the two are judged on the
    // same footing.
    IdentifyCandidate trimmed{ext.fit, json(), ext.label + "-trimmed", {}, ext.check};
    trimmed.fit.model.set_delay((delay + lag) * dt_);
    trimmed.fit.model.configure(dt_);
    IdentifyCandidate again{ext.fit, json(), ext.label + "-again", {}, ext.check};
    s.candidates.push_back(std::move(trimmed));
    s.candidates.push_back(std::move(again));
    s.trim = s.candidates.size() - 2;
    const auto at = s.jobs.begin() + static_cast<std::ptrdiff_t>(s.next);
    s.jobs.insert(at, {{*s.trim, s.fast_hz, true}, {*s.trim + 1, s.fast_hz, true}});
  }
  s.extension["delay_trim"] = std::move(trim);
}

void details::IdentifyCoordinator::settle_delay_trim() {
  if (!session_ || !session_->trim) return;
  IdentifySession& s = *session_;
  IdentifyCandidate& trimmed = s.candidates[*s.trim];
  const IdentifyCandidate& again = s.candidates[*s.trim + 1];
  if (!s.interrupted && !again.sines.contains(s.fast_hz)) return;  // still to play
  IdentifyCandidate& ext = s.candidates[*s.extended];
  const double before = verified_sine_rms(again, s.fast_hz);
  const double after = verified_sine_rms(trimmed, s.fast_hz);
  const auto figure = [](double v) { return std::isfinite(v) ? json(v) : json(); };
  json& trim = s.extension["delay_trim"];
  const bool kept = std::isfinite(before) && after <= kTrimGain * before;
  trim["fast_rms_percent"] = {{"timed", figure(before)}, {"trimmed", figure(after)}};
  trim["logs"] = {{"timed", sine_field(again, s.fast_hz, "log")},
                  {"trimmed", sine_field(trimmed, s.fast_hz, "log")}};
  trim["kept"] = kept;
  trim["why"] = kept ? "the trimmed delay tracks the fast sine better"
                : !std::isfinite(before) || !std::isfinite(after)
                    ? "the trial did not run to the end"
                    : "the trimmed delay does not track the fast sine 3 % better";
  if (kept) {
    // The extension's verified fast sine stays the timed delay's, played as the base's was;
    // the middle sine plays the trimmed model.
    const double samples = trimmed.fit.model.delay_s() / dt_;
    ext.fit.model = std::move(trimmed.fit.model);
    ext.fit.delay_samples = static_cast<int>(std::lround(samples));
    ext.fit.notes.push_back("delay trimmed on the bench's " +
                            compensation::significant(s.fast_hz, 6) + " Hz sine to " +
                            compensation::fixed(samples, 3) + " samples");
  }
  s.candidates.resize(*s.trim);
  s.trim.reset();
}

}  // namespace hystbench::daemon
