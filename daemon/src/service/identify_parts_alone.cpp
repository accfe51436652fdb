// identify's extension, one band of its parts alone: the diagnosis's extended model holds every
// part that gained on the record (a mode and a delay beside creep, a rate law, the loop's shape).
// The fast sine judges the mode and the delay, the triangle and the middle sine the others. An
// extension that gains in one band and gives back in the other would lose all of it: a mode that
// gains on the fast sine beside slow parts that lose on the triangle (their state set at rest
// each run, the actuator's by its history), or a rate law that gains on the middle sine beside a
// mode fitted off the stage's that loses on the fast one. So the base with only the fast parts
// (the extension's mode and delay, timed on the steps, trimmed on the sine), or the extension
// without them (the base's mode and delay), plays the same three references, and is adopted
// where the whole extension is not and it tracks better in its band (finish()). The identify
// coordinator on the supervisor thread (identify_coordinator.hpp).
#include <algorithm>
#include <string>

#include "service/details/identify_coordinator.hpp"
#include "service/details/identify_session.hpp"

namespace hystbench::daemon {

using nlohmann::json;
namespace hc = compensation;

namespace {

bool is_fast_part(const std::string& part) { return part == "delay" || part == "dynamics"; }

std::string joined(const std::vector<std::string>& v) {
  std::string out;
  for (const std::string& s : v) out += (out.empty() ? "" : " + ") + s;
  return out;
}

}  // namespace

const char* parts_key(PartsBand band) {
  return band == PartsBand::kFast ? "fast_parts" : "slow_parts";
}

PartsByBand split_parts(const json& parts) {
  PartsByBand out;
  for (const json& p : parts) {
    const std::string name = p.value("cause", "");
    (is_fast_part(name) ? out.fast : out.slow).push_back(name);
  }
  return out;
}

bool parts_alone_worth_trying(const IdentifyCandidate& base, const IdentifyCandidate& ext,
                              const PartsByBand& parts, PartsBand band, double fast_hz,
                              double mid_hz) {
  if (parts.fast.empty() || parts.slow.empty() || !(fast_hz > 0.0) ||
      extension_tracks_better(base, ext, fast_hz, mid_hz)) {
    return false;
  }
  if (band == PartsBand::kFast) {
    return verified_sine_rms(ext, fast_hz) < verified_sine_rms(base, fast_hz);
  }
  // The slow band where the middle sine gained and the fast one lost: the fast parts lost it.
  return mid_hz > 0.0 && verified_sine_rms(ext, mid_hz) < verified_sine_rms(base, mid_hz) &&
         !(verified_sine_rms(ext, fast_hz) < verified_sine_rms(base, fast_hz));
}

bool adopt_parts_alone(const IdentifyCandidate& base, const IdentifyCandidate& alone,
                       PartsBand band, double fast_hz, double mid_hz, json& extension) {
  json& tried = extension[parts_key(band)];
  const bool adopted = band == PartsBand::kFast
                           ? extension_tracks_better(base, alone, fast_hz, mid_hz)
                           : slow_parts_track_better(base, alone, fast_hz, mid_hz);
  tried["verified"] = verified_gain_json(base, alone, fast_hz, mid_hz);
  tried["adopted"] = adopted;
  tried["why"] =
      adopted ? "they track better on the bench" : "they do not track better on the bench either";
  if (adopted) {
    extension["adopted"] = true;
    extension["why"] = std::string("its ") + (band == PartsBand::kFast ? "fast" : "slow") +
                       " parts alone track better on the bench; the whole extension does not";
  }
  return adopted;
}

void mark_adopted_parts(json& extension, bool extended, std::optional<PartsBand> alone) {
  if (!extension.contains("parts")) return;
  const json in = alone ? extension[parts_key(*alone)]["parts"] : json::array();
  for (json& p : extension["parts"]) {
    const bool in_band = std::find(in.begin(), in.end(), p.value("cause", "")) != in.end();
    p["adopted"] = extended && (!alone || in_band);
  }
}

std::string parts_alone_text(const PartsByBand& parts, PartsBand band) {
  const bool fast = band == PartsBand::kFast;
  return "its " + joined(fast ? parts.fast : parts.slow) + " alone, without " +
         joined(fast ? parts.slow : parts.fast);
}

IdentifyCandidate with_timing_of(const IdentifyCandidate& from, const IdentifyCandidate& timing,
                                 double dt_s) {
  // The static part is from's: so is its check.
  IdentifyCandidate alone{from.fit, json(), from.label, {}, from.check};
  hc::ActuatorModel& m = alone.fit.model;
  m.set_dynamics(timing.fit.model.dynamics());
  m.set_delay(timing.fit.model.delay_s());
  m.configure(dt_s);
  alone.fit.delay_samples = timing.fit.delay_samples;
  return alone;
}

std::optional<IdentifyCandidate> fast_parts_instead(const IdentifyCandidate& base,
                                                    const IdentifyCandidate& ext, double dt_s,
                                                    json& extension) {
  const PartsByBand parts = split_parts(extension.value("parts", json::array()));
  if (parts.fast.empty() || parts.slow.empty()) return std::nullopt;
  IdentifyCandidate fast = with_timing_of(base, ext, dt_s);
  json tried = {{"parts", parts.fast}, {"left_out", parts.slow}};
  const bool checked = passes_check(fast.fit.model, check_of(base, dt_s), dt_s, tried);
  extension[parts_key(PartsBand::kFast)] = std::move(tried);
  if (!checked) return std::nullopt;
  extension["why_fast_parts"] =
      "the whole extension failed its check; its fast parts alone passed it" +
      std::string(extension[parts_key(PartsBand::kFast)]["check"].contains("accepted")
                      ? " (their inverse misses no more than the base's)"
                      : "");
  return fast;
}

void details::IdentifyCoordinator::settle_parts_alone(IdentifySession& s, std::size_t& chosen,
                                                      bool& extended) {
  std::optional<PartsBand> alone = s.extension_band;
  if (alone) {
    // The extension held one band alone (the whole failed its check): that band was judged.
    json& band = s.extension[parts_key(*alone)];
    band["adopted"] = extended;
    band["verified"] = s.extension["verified"];
    band["why"] = s.extension["why"];
  }
  // Else the fast band first (a mode gains the most where it acts).
  for (const PartsBand band : {PartsBand::kFast, PartsBand::kSlow}) {
    const std::optional<std::size_t> c = band == PartsBand::kFast ? s.fast_parts : s.slow_parts;
    if (extended || chosen != s.base || !c ||
        !adopt_parts_alone(s.candidates[s.base], s.candidates[*c], band, s.fast_hz, s.mid_hz,
                           s.extension)) {
      continue;
    }
    extended = true;
    chosen = *c;
    alone = band;
  }
  mark_adopted_parts(s.extension, extended, alone);
}

void details::IdentifyCoordinator::queue_parts_alone() {
  if (!session_) return;
  IdentifySession& s = *session_;
  if (!s.extended || s.extension_band || s.parts_alone_tried || s.trim || s.interrupted ||
      s.next < s.jobs.size()) {
    return;
  }
  s.parts_alone_tried = true;
  const PartsByBand parts = split_parts(s.extension.value("parts", json::array()));
  for (const PartsBand band : {PartsBand::kFast, PartsBand::kSlow}) {
    const IdentifyCandidate &base = s.candidates[s.base], &ext = s.candidates[*s.extended];
    if (!parts_alone_worth_trying(base, ext, parts, band, s.fast_hz, s.mid_hz)) continue;
    const bool fast = band == PartsBand::kFast;
    // The fast parts on the base, or the extension with the base's mode and delay.
    IdentifyCandidate alone =
        fast ? with_timing_of(base, ext, dt_) : with_timing_of(ext, base, dt_);
    alone.fit.notes.push_back("extended by the diagnosis of its record: " +
                              parts_alone_text(parts, band));
    alone.label = base.label + (fast ? "-fast-parts" : "-slow-parts");
    const hc::ActuatorModel& m = alone.fit.model;
    const std::vector<std::string>& in = fast ? parts.fast : parts.slow;
    const std::vector<std::string>& out = fast ? parts.slow : parts.fast;
    json tried = {{"parts", in}, {"left_out", out}};
    const bool checked = passes_check(m, check_of(base, dt_), dt_, tried);
    s.extension[parts_key(band)] = std::move(tried);
    if (!checked) continue;
    s.candidates.push_back(std::move(alone));
    const std::size_t index = s.candidates.size() - 1;
    (fast ? s.fast_parts : s.slow_parts) = index;
    s.jobs.push_back({index, 0.0});
    for (const double hz : {s.fast_hz, s.mid_hz}) {
      if (hz > 0.0) s.jobs.push_back({index, hz});
    }
  }
}

}  // namespace hystbench::daemon
