#include "remote/details/feedback_text.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "hystbench/compensation/number_text.hpp"
#include "remote/details/fixed_text.hpp"

namespace hystbench::cli::details {

using nlohmann::json;

namespace {

// The least (or most) of `key` over the margins, "-" where none is finite.
std::string extreme(const json& margins, const char* key, bool least, int digits) {
  double best =
      least ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
  for (const json& m : margins) {
    if (!m.contains(key) || !m[key].is_number()) continue;
    const double v = m[key].get<double>();
    best = least ? std::min(best, v) : std::max(best, v);
  }
  return std::isfinite(best) ? compensation::fixed(best, digits) : "-";
}

}  // namespace

void print_feedback(std::ostream& out, const json& f) {
  if (!f.is_object()) return;
  const json& margins = f.value("margins", json::array());
  const json& t = f.value("targets", json::object());
  const std::string gains = f.value("gains", std::string("?"));
  out << "  feedback        " << gains;
  if (gains == "designed") {
    out << ": " << f.value("structure", std::string("?"));
  } else {
    const json& law = f.value("law", json::object());
    out << " gains: kp " << fixed_or_dash(law.value("kp", json()), 4) << ", ki "
        << fixed_or_dash(law.value("ki", json()), 1) << " /s, kd "
        << fixed_or_dash(law.value("kd", json()), 6) << " s on the target";
  }
  out << ", through " << f.value("through", std::string("?")) << "\n"
      << "  loop            crossover " << extreme(margins, "crossover_hz", true, 0) << "-"
      << extreme(margins, "crossover_hz", false, 0) << " Hz, closed-loop bandwidth "
      << fixed_or_dash(f.value("bandwidth_hz", json()), 0) << " Hz; |S| at -3 dB from "
      << fixed_or_dash(f.value("rejection_bandwidth_hz", json()), 0) << " Hz, at -20 dB from "
      << fixed_or_dash(f.value("tenfold_rejection_hz", json()), 0) << " Hz\n"
      << "  margins         gain >= " << extreme(margins, "gain_margin_db", true, 1)
      << " dB, phase >= " << extreme(margins, "phase_margin_deg", true, 1)
      << " deg, peak |S| <= " << extreme(margins, "peak_sensitivity_db", false, 1) << " dB on "
      << margins.size() << " responses (targets "
      << fixed_or_dash(t.value("gain_margin_db", json()), 0) << " dB, "
      << fixed_or_dash(t.value("phase_margin_deg", json()), 0) << " deg, "
      << fixed_or_dash(t.value("peak_sensitivity_db", json()), 0) << " dB)";
  const json& robust = f.value("robust", json::object());
  if (robust.value("stable", false)) {
    out << "; stable with the gain +/-" << fixed_or_dash(robust.value("gain", json()), 2)
        << " and the modes moved +/-" << fixed_or_dash(robust.value("mode", json()), 2);
  }
  out << "\n";
  if (f.contains("limited_by")) {
    out << "  limited by      " << f["limited_by"].get<std::string>() << ": "
        << f.value("limit", std::string()) << "\n";
  }
  if (const json& h = f.value("harmonics", json()); h.is_object()) {
    const json& kept = h.value("kept", json::array());
    out << "  harmonics       ";
    if (kept.empty()) {
      out << "no resonator: the loop takes out more than half of each harmonic, or one near a "
             "mode would not hold\n";
    } else {
      out << "resonators at " << kept.size() << " of the reference's harmonics (";
      for (std::size_t i = 0; i < kept.size(); ++i) {
        out << (i > 0 ? ", " : "") << fixed_or_dash(kept[i].value("frequency_hz", json()), 0);
      }
      out << " Hz), settled in about " << fixed_or_dash(h.value("settle_s", json()), 3)
          << " s, where the loop alone leaves more than half\n";
    }
  }
  if (const json& at = f.value("at_reference", json()); at.is_object()) {
    out << "  at reference    |S| " << fixed_or_dash(at.value("sensitivity", json()), 2) << " at "
        << fixed_or_dash(at.value("frequency_hz", json()), 0)
        << " Hz: " << at.value("note", std::string()) << "\n";
  }
  if (f.value("forced", false)) {
    out << "  forced          these gains break a target: " << f.value("broken", std::string())
        << "\n";
  }
}

void print_frequency_response(std::ostream& out, const json& s) {
  if (!s.is_object() || !s.contains("responses")) return;
  const json& list = s["responses"];
  double g_lo = std::numeric_limits<double>::infinity(), g_hi = 0.0, coherence = 1.0, noise = 0.0;
  double f_lo = std::numeric_limits<double>::infinity(), f_hi = 0.0;
  for (const json& r : list) {
    const double g = r.value("low_frequency_gain", 0.0);
    g_lo = std::min(g_lo, g);
    g_hi = std::max(g_hi, g);
    coherence = std::min(coherence, r.value("lowest_coherence", 1.0));
    noise = std::max(noise, r.value("output_noise_rms", 0.0));
    const json band = r.value("band_hz", json::array());
    if (band.size() == 2) {
      f_lo = std::min(f_lo, band[0].get<double>());
      f_hi = std::max(f_hi, band[1].get<double>());
    }
  }
  out << "  response        " << list.size() << " measured, " << fixed_or_dash(f_lo, 0) << "-"
      << fixed_or_dash(f_hi, 0) << " Hz: low-frequency gain " << fixed_or_dash(g_lo, 3) << "-"
      << fixed_or_dash(g_hi, 3) << " um/V, coherence >= " << fixed_or_dash(coherence, 3)
      << ", output noise " << fixed_or_dash(noise * 1e3, 1) << " nm rms\n";
  const json& modes = s.value("modes", json::array());
  if (!modes.empty()) {
    out << "  modes          ";
    for (const json& m : modes) {
      out << " " << fixed_or_dash(m.value("frequency_hz", json()), 0) << " Hz (zeta "
          << fixed_or_dash(m.value("damping_ratio", json()), 3) << ", +"
          << fixed_or_dash(m.value("peak_db", json()), 1) << " dB)";
    }
    out << "\n";
  }
  if (s.contains("moving")) {
    const json& m = s["moving"];
    out << "  while moving    at " << fixed_or_dash(m.value("frequency_hz", json()), 0)
        << " Hz the " << m.value("lagging", std::string("?")) << " ramps lag by "
        << fixed_or_dash(m.value("lag_deg", json()), 2) << " +/- "
        << fixed_or_dash(m.value("lag_noise_deg", json()), 2) << " deg: ";
    if (m.value("zero_hz", json()).is_number()) {
      out << "a rate law's zero at " << fixed_or_dash(m["zero_hz"], 0) << " Hz\n";
    } else {
      out << "no rate law's zero\n";
    }
  }
  if (s.contains("change")) {
    const json& c = s["change"];
    out << "  since           " << c.value("since", std::string("?")) << ": gain x"
        << fixed_or_dash(c.value("gain_ratio", json()), 3);
    if (c.contains("mode_hz")) {
      out << ", first mode " << fixed_or_dash(c["mode_hz"][0], 0) << " -> "
          << fixed_or_dash(c["mode_hz"][1], 0) << " Hz";
    }
    out << "\n";
  }
}

}  // namespace hystbench::cli::details
