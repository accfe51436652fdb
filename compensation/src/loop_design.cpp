#include "hystbench/compensation/loop_design.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "details/validate.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// A point of the loop within this share of a mode's frequency is that mode's doing.
constexpr double kNearMode = 0.35;
// The integral gain's scan: from a crossover of this share of the loop rate, up by kScanStep
// until a target breaks, then halved kBisections times between the last gain that held and it.
constexpr double kScanStartFraction = 1e-4;
constexpr double kScanTopFraction = 0.25;
constexpr double kScanStep = 1.3;
constexpr int kBisections = 6;
// A structure replaces a simpler one only when its bandwidth is this much higher.
constexpr double kBetterBy = 1.03;
// What a higher gain breaks, for `limited_by`: this much higher than the design's.
constexpr double kLimitProbe = 1.1;

// The loop's shape, its gains scaled by the integral crossover f_n = ki g / (2 pi), g the
// responses' low-frequency gain: kp = p / g, the low-pass at lp_ratio x f_n (0: none), the boost
// at boost_ratio x f_n (0: none) lifting the gain below it by boost_gain.
struct Shape {
  std::vector<Notch> notches;
  double p = 0.0;
  double lp_ratio = 0.0;
  double boost_ratio = 0.0;
  double boost_gain = 1.0;
};

std::string near_mode(double f, const std::vector<MeasuredMode>& modes) {
  for (const MeasuredMode& m : modes) {
    if (std::abs(f / m.frequency_hz - 1.0) <= kNearMode) return significant(m.frequency_hz, 6);
  }
  return "";
}

// The responses with the lowest and the highest low-frequency gain, each with its gain moved
// by -/+ u, and with the gain raised and each mode moved by -/+ m.
std::vector<MeasuredResponse> robust_variants(std::span<const MeasuredResponse> responses,
                                              const std::vector<MeasuredMode>& modes,
                                              const LoopDesignOptions& o,
                                              std::vector<std::string>& names) {
  std::size_t lo = 0, hi = 0;
  for (std::size_t i = 1; i < responses.size(); ++i) {
    const double g = low_frequency_gain(responses[i]);
    if (g < low_frequency_gain(responses[lo])) lo = i;
    if (g > low_frequency_gain(responses[hi])) hi = i;
  }
  std::vector<MeasuredResponse> out;
  auto scaled = [](MeasuredResponse r, double k) {
    for (auto& x : r.response) x *= k;
    return r;
  };
  const double up = 1.0 + o.gain_uncertainty, down = 1.0 - o.gain_uncertainty;
  for (const std::size_t i :
       (lo == hi ? std::vector<std::size_t>{lo} : std::vector<std::size_t>{lo, hi})) {
    const std::string of = " (" + responses[i].label + ")";
    if (o.gain_uncertainty > 0.0) {
      out.push_back(scaled(responses[i], up));
      names.push_back("the gain x" + significant(up, 6) + of);
      out.push_back(scaled(responses[i], down));
      names.push_back("the gain x" + significant(down, 6) + of);
    }
    if (o.rhp_zero_hz > 0.0) {
      MeasuredResponse z = responses[i];
      for (std::size_t j = 0; j < z.size(); ++j) {
        z.response[j] *= std::complex<double>(1.0, -z.frequency_hz[j] / o.rhp_zero_hz);
      }
      out.push_back(std::move(z));
      names.push_back("rate_law:" + o.rhp_zero_reason + ", a zero at " +
                      significant(o.rhp_zero_hz, 6) + " Hz" + of);
    }
    if (o.mode_uncertainty <= 0.0) continue;
    for (std::size_t k = 0; k < std::min<std::size_t>(modes.size(), 2); ++k) {
      for (const double f : {1.0 - o.mode_uncertainty, 1.0 + o.mode_uncertainty}) {
        out.push_back(scaled(with_mode_moved(responses[i], modes[k], f, o.dt_s), up));
        names.push_back("the gain x" + significant(up, 6) + " and the mode at " +
                        significant(modes[k].frequency_hz, 6) + " Hz moved to " +
                        significant(modes[k].frequency_hz * f, 6) + " Hz" + of);
      }
    }
  }
  return out;
}

// The rms of v over that of white output noise through the loop: v = -C S n, so
// (v / n)^2 = the mean of |C S|^2 over [0, Nyquist] (|C S| held below the lowest line).
// c: C at the lines and the Nyquist frequency, as l.
double drive_noise_gain(const std::vector<std::complex<double>>& c, const MeasuredResponse& p,
                        const std::vector<std::complex<double>>& l, double dt) {
  std::vector<double> f(p.frequency_hz.begin(), p.frequency_hz.end());
  f.push_back(0.5 / dt);
  std::vector<double> cs2(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) cs2[i] = std::norm(c[i] / (1.0 + l[i]));
  double integral = cs2[0] * f[0];
  for (std::size_t i = 1; i < f.size(); ++i)
    integral += 0.5 * (cs2[i] + cs2[i - 1]) * (f[i] - f[i - 1]);
  return std::sqrt(integral / f.back());
}

class Evaluator {
 public:
  Evaluator(std::span<const MeasuredResponse> responses, const std::vector<MeasuredMode>& modes,
            const LoopDesignOptions& o)
      : responses_(responses), modes_(modes), o_(o) {
    variants_ = robust_variants(responses, modes, o, variant_names_);
  }

  LoopEvaluation operator()(const FeedbackLaw& law) const {
    LoopEvaluation e;
    FeedbackController c(law, o_.dt_s);
    const bool integrator = law.pid.ki > 0.0;
    e.meets_targets = true;
    e.crossover_hz = e.bandwidth_hz = e.rejection_bandwidth_hz = e.tenfold_rejection_hz =
        std::numeric_limits<double>::infinity();
    std::vector<std::complex<double>> controller;
    for (const MeasuredResponse& r : responses_) {
      const std::vector<std::complex<double>> l = loop_response(r, c, o_.dt_s, &controller);
      const LoopMargins m = loop_margins(r, l, integrator, o_.dt_s);
      e.margins.push_back(m);
      e.crossover_hz = std::min(e.crossover_hz, m.crossover_hz);
      e.bandwidth_hz = std::min(e.bandwidth_hz, m.bandwidth_hz);
      e.rejection_bandwidth_hz = std::min(e.rejection_bandwidth_hz, m.rejection_bandwidth_hz);
      e.tenfold_rejection_hz = std::min(e.tenfold_rejection_hz, m.tenfold_rejection_hz);
      e.output_noise_rms = std::max(e.output_noise_rms, r.output_noise_rms);
      e.drive_noise_rms = std::max(
          e.drive_noise_rms, drive_noise_gain(controller, r, l, o_.dt_s) * r.output_noise_rms);
      if (!meets(m, o_.targets)) {
        if (e.meets_targets) describe_failure(m, r, e);
        e.meets_targets = false;
      }
    }
    if (o_.max_crossover_hz > 0.0) {
      for (const LoopMargins& m : e.margins) {
        if (m.crossover_hz > o_.max_crossover_hz && e.failure.empty()) {
          e.meets_targets = false;
          e.failure_kind = "rate_law";
          e.failure_hz = m.crossover_hz;
          e.failure = "the crossover " + significant(m.crossover_hz, 6) + " Hz is above " +
                      significant(o_.max_crossover_hz, 6) + " Hz (" + o_.max_crossover_reason + ")";
        }
      }
    }
    e.quiet = e.drive_noise_rms <= o_.output_noise_budget * e.output_noise_rms;
    if (!e.quiet && e.failure.empty()) {
      e.failure_kind = "sensor";
      e.failure = "the drive noise " + significant(e.drive_noise_rms, 6) + " is above " +
                  significant(o_.output_noise_budget, 6) + " x the sensor's " +
                  significant(e.output_noise_rms, 6);
    }
    e.robust = true;
    if (!e.meets_targets) return e;  // a variant check is for a loop that holds as measured
    const LoopTargets variant_targets{o_.variant_gain_margin_db, -180.0,
                                      o_.variant_peak_sensitivity_db};
    for (std::size_t i = 0; i < variants_.size(); ++i) {
      const LoopMargins m = loop_margins(variants_[i], c, o_.dt_s);
      if (!meets(m, variant_targets)) {
        e.robust = false;
        if (e.failure.empty()) {
          // A variant named "rate_law:..." is the rate law's zero, the others the gain and modes.
          std::string name = variant_names_[i];
          e.failure_kind = "robustness";
          if (name.rfind("rate_law:", 0) == 0) {
            e.failure_kind = "rate_law";
            name = name.substr(9);
          }
          e.failure = (m.stable ? "too close to instability (gain margin " +
                                      significant(m.gain_margin_db, 6) + " dB, peak |S| " +
                                      significant(m.peak_sensitivity_db, 6) + " dB)"
                                : std::string("unstable")) +
                      " with " + name;
        }
        break;
      }
    }
    return e;
  }

 private:
  void describe_failure(const LoopMargins& m, const MeasuredResponse& r, LoopEvaluation& e) const {
    const LoopTargets& t = o_.targets;
    const std::string on = " on " + r.label;
    auto kind_at = [&](double f, const char* otherwise) {
      const std::string mode = near_mode(f, modes_);
      e.failure_hz = f;
      e.failure_kind = mode.empty() ? otherwise : "mode";
      return mode.empty() ? std::string() : " (the mode at " + mode + " Hz)";
    };
    if (!m.stable) {
      const std::string mode = kind_at(m.peak_sensitivity_hz, "delay");
      e.failure = "unstable" + on + ": " + std::to_string(m.unstable_poles) +
                  " closed-loop poles outside the unit circle, |S| peaks at " +
                  significant(m.peak_sensitivity_hz, 6) + " Hz" + mode;
    } else if (m.gain_margin_db < t.gain_margin_db) {
      const std::string mode = kind_at(m.gain_margin_hz, "delay");
      e.failure = "gain margin " + significant(m.gain_margin_db, 6) + " dB at " +
                  significant(m.gain_margin_hz, 6) + " Hz" + mode + on;
    } else if (m.phase_margin_deg < t.phase_margin_deg) {
      const std::string mode = kind_at(m.crossover_hz, "delay");
      e.failure = "phase margin " + significant(m.phase_margin_deg, 6) + " deg at the " +
                  significant(m.crossover_hz, 6) + " Hz crossover" + mode + on;
    } else {
      const std::string mode = kind_at(m.peak_sensitivity_hz, "sensitivity");
      e.failure = "peak |S| " + significant(m.peak_sensitivity_db, 6) + " dB at " +
                  significant(m.peak_sensitivity_hz, 6) + " Hz" + mode + on;
    }
  }

  std::span<const MeasuredResponse> responses_;
  const std::vector<MeasuredMode>& modes_;
  const LoopDesignOptions& o_;
  std::vector<MeasuredResponse> variants_;
  std::vector<std::string> variant_names_;
};

FeedbackLaw law_for(const Shape& s, double fn_hz, double g, const LoopDesignOptions& o) {
  FeedbackLaw law;
  law.pid.ki = kTwoPi * fn_hz / g;
  law.pid.kp = s.p / g;
  law.pid.output_min = -o.output_limit;
  law.pid.output_max = o.output_limit;
  law.shaping.notches = s.notches;
  if (s.lp_ratio > 0.0)
    law.shaping.low_pass.frequency_hz = std::min(s.lp_ratio * fn_hz, 0.45 / o.dt_s);
  if (s.boost_ratio > 0.0) law.boost = {s.boost_ratio * fn_hz, s.boost_gain};
  return law;
}

std::string describe(const FeedbackLaw& law) {
  std::string s = law.pid.kp > 0.0 ? "PI" : "integral";
  if (law.boost.frequency_hz > 0.0) {
    s += ", boost x" + significant(law.boost.gain, 6) + " below " +
         significant(law.boost.frequency_hz, 6) + " Hz";
  }
  for (const Notch& n : law.shaping.notches)
    s += ", notch at " + significant(n.frequency_hz, 6) + " Hz";
  if (law.shaping.low_pass.frequency_hz > 0.0)
    s += ", low-pass " + significant(law.shaping.low_pass.frequency_hz, 6) + " Hz";
  return s;
}

std::vector<Shape> shapes(const std::vector<MeasuredMode>& modes, const LoopDesignOptions& o) {
  std::vector<std::vector<Notch>> notch_sets = {{}};
  const std::size_t most = std::min({modes.size(), o.max_notches, ShapingFilter::kMaxNotches});
  for (const double width : {0.25, 0.5}) {
    std::vector<Notch> set;
    for (std::size_t k = 0; k < most; ++k) {
      if (modes[k].frequency_hz >= 0.45 / o.dt_s) continue;
      set.push_back({modes[k].frequency_hz, width, 0.1});
      notch_sets.push_back(set);
    }
  }
  struct Boost {
    double ratio, gain;
  };
  std::vector<Shape> out;
  for (const auto& notches : notch_sets) {
    for (const double p : {0.0, 0.2, 0.4}) {
      for (const double lp : {0.0, 2.5, 5.0}) {
        for (const Boost b : {Boost{0.0, 1.0}, Boost{1.0 / 3.0, 10.0}, Boost{0.2, 20.0}}) {
          out.push_back({notches, p, lp, b.ratio, b.gain});
        }
      }
    }
  }
  return out;
}

}  // namespace

LoopEvaluation check_loop(std::span<const MeasuredResponse> responses, const FeedbackLaw& law,
                          const LoopDesignOptions& o) {
  details::require(!responses.empty(), "loop check: no measured response");
  for (std::size_t i = 0; i < responses.size(); ++i) {
    validate(responses[i], "responses[" + std::to_string(i) + "]");
  }
  const std::vector<MeasuredMode> modes = measured_modes(responses);
  return Evaluator(responses, modes, o)(law);
}

LoopDesign design_loop(std::span<const MeasuredResponse> responses, const LoopDesignOptions& o) {
  details::require(!responses.empty(), "loop design: no measured response");
  details::require(std::isfinite(o.dt_s) && o.dt_s > 0.0, "loop design: dt must be > 0");
  details::require(o.gain_uncertainty >= 0.0 && o.gain_uncertainty < 1.0,
                   "loop design: gain_uncertainty must be in [0, 1)");
  details::require(o.mode_uncertainty >= 0.0 && o.mode_uncertainty < 1.0,
                   "loop design: mode_uncertainty must be in [0, 1)");
  for (std::size_t i = 0; i < responses.size(); ++i) {
    validate(responses[i], "responses[" + std::to_string(i) + "]");
  }
  LoopDesign d;
  d.modes = measured_modes(responses);
  const Evaluator evaluate(responses, d.modes, o);
  double g = 0.0;
  for (const MeasuredResponse& r : responses) g = std::max(g, low_frequency_gain(r));
  details::require(g > 0.0, "loop design: the responses have no gain");
  const double rate = 1.0 / o.dt_s;
  double best = 0.0;
  Shape best_shape;
  double best_fn = 0.0;
  for (const Shape& s : shapes(d.modes, o)) {
    double fn = kScanStartFraction * rate, ok = 0.0;
    LoopEvaluation ok_eval;
    while (fn < kScanTopFraction * rate) {
      LoopEvaluation e = evaluate(law_for(s, fn, g, o));
      if (!e.ok()) break;
      ok = fn;
      ok_eval = std::move(e);
      fn *= kScanStep;
    }
    if (ok == 0.0) continue;
    double hi = fn;
    for (int i = 0; i < kBisections && hi < kScanTopFraction * rate; ++i) {
      const double mid = std::sqrt(ok * hi);
      LoopEvaluation e = evaluate(law_for(s, mid, g, o));
      if (e.ok()) {
        ok = mid;
        ok_eval = std::move(e);
      } else {
        hi = mid;
      }
    }
    // Where |S| reaches -20 dB, then -3 dB, then the crossover (a weak loop reaches -20 dB
    // nowhere in the band).
    const double merit = ok_eval.tenfold_rejection_hz + 1e-3 * ok_eval.rejection_bandwidth_hz +
                         1e-6 * ok_eval.crossover_hz;
    if (!d.found || merit > best * kBetterBy) {
      best = merit;
      best_shape = s;
      best_fn = ok;
      d.evaluation = std::move(ok_eval);
      d.found = true;
    }
  }
  if (!d.found) {
    d.limited_by = "targets";
    d.limit = "no loop meets the targets on the measured responses, even at a crossover of " +
              significant(kScanStartFraction * rate, 6) + " Hz";
    return d;
  }
  d.law = law_for(best_shape, best_fn, g, o);
  d.structure = describe(d.law);
  const LoopEvaluation above = evaluate(law_for(best_shape, best_fn * kLimitProbe, g, o));
  if (best_fn * kScanStep >= kScanTopFraction * rate || above.ok()) {
    d.limited_by = "loop_rate";
    d.limit =
        "the scan's top, a crossover of " + significant(kScanTopFraction, 6) + " x the loop rate";
  } else {
    d.limited_by = above.failure_kind;
    d.limit = significant((kLimitProbe - 1.0) * 100.0, 6) +
              " % more gain breaks a target: " + above.failure;
  }
  return d;
}

}  // namespace hystbench::compensation
