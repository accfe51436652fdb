// identify's extension, its fast parts alone: the diagnosis's extended model holds every part
// that gained on the record (a mode and a delay beside creep, a rate law, the loop's shape). The
// fast sine judges the mode and the delay, the triangle and the middle sine the others; an
// extension that gains on the fast sine but gives back on the triangle (its slow parts' state
// set at rest each run, the actuator's by its history) would lose all of it. So the base with
// only the extension's mode and delay (timed on the steps, trimmed on the sine) plays the same
// three references, and is adopted where the whole extension is not and it tracks better
// (finish_identify). Bench members on the supervisor thread (identify_session.hpp).
#include <algorithm>
#include <string>

#include "runs/details/identify_session.hpp"

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

PartsByBand split_parts(const json& parts) {
  PartsByBand out;
  for (const json& p : parts) {
    const std::string name = p.value("cause", "");
    (is_fast_part(name) ? out.fast : out.slow).push_back(name);
  }
  return out;
}

bool fast_parts_worth_trying(const IdentifyCandidate& base, const IdentifyCandidate& ext,
                             const PartsByBand& parts, double fast_hz, double mid_hz) {
  return !parts.fast.empty() && !parts.slow.empty() && fast_hz > 0.0 &&
         !extension_tracks_better(base, ext, fast_hz, mid_hz) &&
         verified_sine_rms(ext, fast_hz) < verified_sine_rms(base, fast_hz);
}

bool adopt_fast_parts(const IdentifyCandidate& base, const IdentifyCandidate& alone, double fast_hz,
                      double mid_hz, json& extension) {
  json& tried = extension["fast_parts"];
  const bool adopted = extension_tracks_better(base, alone, fast_hz, mid_hz);
  tried["verified"] = verified_gain_json(base, alone, fast_hz, mid_hz);
  tried["adopted"] = adopted;
  tried["why"] =
      adopted ? "they track better on the bench" : "they do not track better on the bench either";
  if (adopted) {
    extension["adopted"] = true;
    extension["why"] =
        "its fast parts alone track better on the bench; the whole extension does not";
  }
  return adopted;
}

void mark_adopted_parts(json& extension, bool extended, bool fast_parts_only) {
  if (!extension.contains("parts")) return;
  const json fast = fast_parts_only ? extension["fast_parts"]["parts"] : json::array();
  for (json& p : extension["parts"]) {
    const bool in_fast = std::find(fast.begin(), fast.end(), p.value("cause", "")) != fast.end();
    p["adopted"] = extended && (!fast_parts_only || in_fast);
  }
}

void Bench::queue_fast_parts() {
  if (!session_) return;
  IdentifySession& s = *session_;
  if (!s.extended || s.fast_parts_tried || s.trim || s.interrupted || s.next < s.jobs.size()) {
    return;
  }
  s.fast_parts_tried = true;
  const PartsByBand parts = split_parts(s.extension.value("parts", json::array()));
  const IdentifyCandidate &base = s.candidates[s.base], &ext = s.candidates[*s.extended];
  if (!fast_parts_worth_trying(base, ext, parts, s.fast_hz, s.mid_hz)) return;
  IdentifyCandidate alone{base.fit, json(), base.label + "-fast-parts", {}};
  hc::ActuatorModel& m = alone.fit.model;
  m.set_dynamics(ext.fit.model.dynamics());
  m.set_delay(ext.fit.model.delay_s());
  m.configure(dt_);
  alone.fit.delay_samples = ext.fit.delay_samples;
  alone.fit.notes.push_back("extended by the diagnosis of its record: its " + joined(parts.fast) +
                            " alone, without " + joined(parts.slow));
  json tried = {{"parts", parts.fast}, {"left_out", parts.slow}};
  if (!passes_check(m, dt_, tried)) {
    s.extension["fast_parts"] = std::move(tried);
    return;
  }
  s.extension["fast_parts"] = std::move(tried);
  s.candidates.push_back(std::move(alone));
  s.fast_parts = s.candidates.size() - 1;
  s.jobs.push_back({*s.fast_parts, 0.0});
  for (const double hz : {s.fast_hz, s.mid_hz}) {
    if (hz > 0.0) s.jobs.push_back({*s.fast_parts, hz});
  }
}

}  // namespace hystbench::daemon
