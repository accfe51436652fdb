#include "remote/details/identify_text.hpp"

#include <string>

#include "remote/details/fixed_text.hpp"

namespace hystbench::cli::details {

using nlohmann::json;

namespace {

// The extension's delay trimmed on its fast sine: the lag measured, and what the bench kept.
void print_delay_trim(std::ostream& out, const json& t) {
  const double delay = t.value("delay_samples", 0.0), lag = t.value("lag_samples", 0.0);
  out << "  extension delay " << fixed(delay, 2) << " samples; the "
      << fixed(t.value("sine_hz", 0.0), 0) << " Hz sine lags by " << fixed(lag, 3);
  if (t.contains("fast_rms_percent")) {
    const json& rms = t["fast_rms_percent"];
    out << ", trimmed to " << fixed(delay + lag, 2) << " samples: rms "
        << fixed_or_dash(rms.value("timed", json()), 3) << " -> "
        << fixed_or_dash(rms.value("trimmed", json()), 3) << " %";
  }
  out << ": " << (t.value("kept", false) ? "kept" : "not kept") << ", " << t.value("why", "")
      << "\n";
}

// A check that failed and was passed all the same: `who`'s inverse misses no more than its base's.
void print_accepted_check(std::ostream& out, const json& check, const std::string& who) {
  if (!check.contains("accepted")) return;
  out << "  " << who << " checked: driven by its inverse it misses a triangle over 90 % of its "
      << "range by " << fixed_or_dash(check.value("inverse_rms_percent", json()), 3)
      << " % rms, its base by "
      << fixed_or_dash(check.value("base", json::object()).value("inverse_rms_percent", json()), 3)
      << " %: played, as " << check["accepted"].get<std::string>() << "\n";
}

// "delay + creep": the names of a list of parts.
std::string names(const json& list) {
  std::string s;
  for (const json& n : list) s += (s.empty() ? "" : " + ") + n.get<std::string>();
  return s;
}

// One band of an extension's parts tried alone (model.extension.fast_parts / slow_parts).
void print_parts_alone(std::ostream& out, const json& f, const std::string& band) {
  out << "  extension " << band << "  " << names(f.value("parts", json::array()))
      << " alone (without " << names(f.value("left_out", json::array())) << ")";
  if (f.contains("verified")) {
    const json& v = f["verified"];
    out << ": triangle rms " << fixed_or_dash(v["triangle_rms_percent"].value("model", json()), 3)
        << " -> " << fixed_or_dash(v["triangle_rms_percent"].value("extended", json()), 3) << " %";
    for (const char* sine : {"fast", "mid"}) {
      const std::string hz = std::string(sine) + "_hz", rms = std::string(sine) + "_rms_percent";
      if (!v.contains(hz) || !v[hz].is_number()) continue;
      out << ", " << fixed(v[hz].get<double>(), 0) << " Hz sine rms "
          << fixed_or_dash(v[rms].value("model", json()), 3) << " -> "
          << fixed_or_dash(v[rms].value("extended", json()), 3) << " %";
    }
  }
  out << ": " << (f.value("adopted", false) ? "adopted" : "not adopted") << ", "
      << f.value("why", std::string("not judged: the verification did not complete")) << "\n";
  print_accepted_check(out, f.value("check", json::object()), "extension " + band);
}

// identify's extension: each part with its held-out gain, the verified figures, the decision.
void print_extension(std::ostream& out, const json& e) {
  out << "  extension       ";
  const json parts = e.value("parts", json::array());
  for (std::size_t i = 0; i < parts.size(); ++i) {
    out << (i ? " + " : "") << parts[i].value("cause", "?") << " (held-out gain "
        << fixed_or_dash(parts[i].value("heldout_gain", json()), 2) << "x)";
  }
  if (parts.empty()) out << "nothing added";
  out << ": " << (e.value("adopted", false) ? "adopted" : "not adopted") << ", "
      << e.value("why", std::string()) << "\n";
  const json check = e.value("check", json::object());
  if (check.value("passed", false)) {
    out << "  extension model checked: driven by its inverse it tracks a triangle over 90 % of its "
           "range at "
        << fixed_or_dash(check.value("inverse_rms_percent", json()), 3) << " % rms\n";
  } else {
    print_accepted_check(out, check, "extension model");
  }
  if (e.contains("verified")) {
    const json& v = e["verified"];
    out << "  extension check triangle max "
        << fixed_or_dash(v["triangle_max_percent"].value("model", json()), 3) << " -> "
        << fixed_or_dash(v["triangle_max_percent"].value("extended", json()), 3) << " %";
    for (const char* sine : {"fast", "mid"}) {
      const std::string hz = std::string(sine) + "_hz";
      if (!v.contains(hz)) continue;
      const json& rms = v[std::string(sine) + "_rms_percent"];
      out << ", " << fixed(v[hz].get<double>(), 0) << " Hz sine rms "
          << fixed_or_dash(rms.value("model", json()), 3) << " -> "
          << fixed_or_dash(rms.value("extended", json()), 3) << " %";
    }
    out << "\n";
    if (e.contains("timing")) {
      const json& t = e["timing"];
      out << "  extension timed on " << t.value("steps", 0)
          << " step responses: " << fixed_or_dash(t.value("natural_frequency_hz", json()), 0)
          << " Hz, damping " << fixed_or_dash(t.value("damping_ratio", json()), 3) << ", delay "
          << fixed_or_dash(t.value("delay_samples", json()), 2) << " samples\n";
    }
    if (e.contains("delay_trim")) print_delay_trim(out, e["delay_trim"]);
  }
  if (e.contains("after_timing")) {
    const std::string named = names(e["after_timing"].value("named", json::array()));
    out << "  extension diagnosed again on the timed mode and delay: "
        << (named.empty() ? "nothing more named" : "named " + named) << "\n";
  }
  if (e.contains("fast_parts")) print_parts_alone(out, e["fast_parts"], "fast");
  if (e.contains("slow_parts")) print_parts_alone(out, e["slow_parts"], "slow");
}

// identify's model: its structure and file, its fit and held-out errors, the fit's notes.
void print_model(std::ostream& out, const json& m) {
  const bool plane = m.value("type", "") == "preisach";
  out << "  model           " << m.value("type", "?") << ", " << m.value("operators", 0)
      << (plane ? " cells per side, " : " plays, ") << m.value("dead_zones", 0)
      << " dead zones per side -> " << m.value("path", "?") << "\n";
  if (m.contains("heldout")) {
    out << "  model error     fit rms " << fixed(m["fit"]["rmse"], 4) << " um, held-out rms "
        << fixed(m["heldout"]["rmse"], 4) << " um (" << fixed(m["heldout"]["rmse_percent"], 3)
        << " %), max " << fixed(m["heldout"]["max_abs"], 4) << " um\n";
  }
  for (const json& note : m.value("notes", json::array())) {
    out << "  fit note        " << note.get<std::string>() << "\n";
  }
}

// identify's verification through the inverse: its tracking error, or why it did not run.
void print_verification(std::ostream& out, const json& v) {
  out << "  verified        ";
  if (v.contains("max_error_percent")) {
    out << "tracking rms " << fixed(v["rms_error_percent"], 3) << " %, max "
        << fixed(v["max_error_percent"], 3) << " % (1 Hz triangle through the inverse, "
        << v.value("end", "?") << ")\n";
  } else {
    out << "not (" << v.value("end", "?") << ": " << v.value("reason", "") << ")\n";
  }
}

// Whether identify kept the rate law: the sine's error without it and with it.
void print_rate_law(std::ostream& out, const json& law) {
  out << "  rate law        " << (law.value("kept", false) ? "kept" : "left out") << ": "
      << fixed_or_dash(law.value("sine_hz", json()), 0) << " Hz sine rms "
      << fixed_or_dash(law["sine_rms_percent"].value("rate_free", json()), 3) << " % without, "
      << fixed_or_dash(law["sine_rms_percent"].value("law", json()), 3) << " % with it\n";
}

// identify's other candidates: each one's held-out and verified error.
void print_candidates(std::ostream& out, const json& candidates) {
  for (const json& c : candidates) {
    const json& v = c["verification"];
    out << "  candidate       " << c.value("type", "?") << " " << c.value("operators", 0) << "/"
        << c.value("dead_zones", 0) << ": held-out rms " << fixed(c["heldout"]["rmse_percent"], 3)
        << " %, verified max "
        << (v.is_object() && v.contains("max_error_percent") ? fixed(v["max_error_percent"], 3)
                                                             : std::string("-"))
        << " %\n";
  }
}

}  // namespace

void print_identification(std::ostream& out, const json& r) {
  if (r.contains("model")) print_model(out, r["model"]);
  if (r.contains("verification") && r["verification"].is_object()) {
    print_verification(out, r["verification"]);
  }
  if (r.contains("model") && r["model"].contains("rate_law")) {
    print_rate_law(out, r["model"]["rate_law"]);
  }
  if (r.contains("model") && r["model"].contains("extension"))
    print_extension(out, r["model"]["extension"]);
  print_candidates(out, r.value("candidates", json::array()));
}

}  // namespace hystbench::cli::details
