#include "runs/details/track_reference.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "hystbench/common/command_error.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::daemon::details {

using compensation::significant;
using nlohmann::json;

namespace {

/// Names the upload's sample k as the client knows it (the k-th value it sent).
std::string sample_words(const Upload& u, std::size_t k) {
  return "sample " + std::to_string(k) + " (t = " + significant(u.time_of(k), 6) + " s" +
         (u.source.empty() ? "" : " of " + u.source) + ")";
}

/// Every value within [lo, hi], else out_of_range naming the first one outside.
void check_range(const Upload& u, double lo, double hi, const char* unit, const char* what) {
  for (std::size_t k = 0; k < u.values.size(); ++k) {
    const double v = u.values[k];
    if (v < lo - 1e-9 || v > hi + 1e-9) {
      throw common::CommandError(
          "out_of_range",
          std::string(what) + " " + sample_words(u, k) + ": " + significant(v, 6) + " " + unit +
              " is beyond the " + (unit[0] == 'V' ? "output" : "actuator") + " range [" +
              significant(lo, 6) + ", " + significant(hi, 6) + "] " + unit + "; nothing ran",
          {{"sample", k}, {"t_s", u.time_of(k)}});
    }
  }
}

/// The resampled values move at most max_step per tick, else slew_limit naming the sample.
void check_slew(const Upload& u, const std::vector<double>& v, double max_step, double dt_s,
                double limit_per_s, const char* unit, const char* what) {
  for (std::size_t k = 1; k < v.size(); ++k) {
    const double step = std::abs(v[k] - v[k - 1]);
    if (step > max_step * (1.0 + 1e-9) + 1e-12) {
      const std::size_t s = u.sample_from(static_cast<double>(k) * dt_s);
      throw common::CommandError("slew_limit",
                                 std::string(what) + " " + sample_words(u, s) + ": moves " +
                                     significant(step / dt_s, 6) + " " + unit +
                                     "/s, faster than the slew limit " +
                                     significant(limit_per_s, 6) + " " + unit + "/s; nothing ran",
                                 {{"sample", s}, {"t_s", u.time_of(s)}});
    }
  }
}

/// A raised cosine of n ticks from `from` towards `to` (its last tick one short of `to`).
std::vector<double> approach(double from, double to, std::size_t n) {
  std::vector<double> v(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double f = 0.5 * (1.0 - std::cos(M_PI * static_cast<double>(k) / n));
    v[k] = from + f * (to - from);
  }
  return v;
}

/// FNV-1a over the values to a picometre: a trajectory's identity for its learned drive.
std::string signature_of(const std::vector<double>& values) {
  std::uint64_t h = 1469598103934665603ULL;
  for (const double v : values) {
    auto q = static_cast<std::uint64_t>(std::llround(v * 1e6));
    for (int b = 0; b < 8; ++b, q >>= 8) {
      h ^= q & 0xffU;
      h *= 1099511628211ULL;
    }
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

/// The fundamental [Hz] of a trajectory sampled every dt_s: its reversals (moves back by more
/// than 2 % of its span) over twice its duration; 0 for one that never turns.
double reversal_rate(const std::vector<double>& v, double dt_s) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const double band = 0.02 * (*hi - *lo);
  if (!(band > 0.0)) return 0.0;
  std::size_t reversals = 0;
  int direction = 0;  // +1 rising, -1 falling, 0 not yet known
  double low = v.front(), high = v.front(), extreme = v.front();
  for (const double x : v) {
    if (direction == 0) {
      low = std::min(low, x);
      high = std::max(high, x);
      direction = x > low + band ? 1 : x < high - band ? -1 : 0;
      extreme = x;
    } else if (direction * (x - extreme) > 0.0) {
      extreme = x;  // further the same way
    } else if (std::abs(x - extreme) > band) {
      ++reversals;
      direction = -direction;
      extreme = x;
    }
  }
  return static_cast<double>(reversals) / (2.0 * static_cast<double>(v.size()) * dt_s);
}

/// A trajectory in passes: the first pass's ticks, then the later passes' (each P ticks), linear
/// in between, the end held. Real-time safe.
class RepeatedPasses final : public sim::SignalGenerator {
 public:
  RepeatedPasses(std::vector<double> first, std::vector<double> later, std::size_t passes,
                 double dt_s)
      : first_(std::move(first)),
        later_(std::move(later)),
        samples_(passes * first_.size()),
        dt_s_(dt_s) {}
  double value(double t_s) const noexcept override {
    const double x = t_s / dt_s_;
    if (!(x > 0.0)) return first_.front();  // before the start, and NaN
    const double last = static_cast<double>(samples_ - 1);
    if (x >= last) return at(samples_ - 1);
    const auto k = static_cast<std::size_t>(x);
    const double f = x - static_cast<double>(k);
    return at(k) + f * (at(k + 1) - at(k));
  }
  double duration_s() const noexcept override { return static_cast<double>(samples_ - 1) * dt_s_; }

 private:
  double at(std::size_t k) const noexcept {
    const std::size_t p = first_.size();
    return k < p ? first_[k] : later_[k % p];
  }
  std::vector<double> first_, later_;
  std::size_t samples_;
  double dt_s_;
};

// A period on the wall clock may begin before the learner's update for it is ready: a learning
// run is long enough for this much update time per trial, and ends after its last trial.
constexpr double kUpdateAllowanceS = 0.05;

}  // namespace

TrackReference builtin_reference(const BuiltinReferenceRequest& request,
                                 const ReferenceLimits& limits, double frequency_hz,
                                 double periods_given) {
  const std::string& ref_name = request.name;
  sim::SignalSpec spec;
  spec.kind = request.kind;
  spec.frequency_hz = frequency_hz > 0.0 ? frequency_hz : request.frequency_hz;
  const double periods = periods_given > 0.0 ? periods_given : request.periods;
  double duration = periods_given > 0.0 ? 0.0 : request.duration_s;
  if (duration <= 0.0) duration = periods / spec.frequency_hz;
  if (!(duration > 0.0)) {
    throw common::CommandError("bad_params", "periods or duration_s must be > 0");
  }

  const double span = limits.y_top - limits.y_bottom;
  const double fraction = request.range_fraction;
  double y_lo = limits.y_bottom + 0.5 * (1.0 - fraction) * span;
  double y_hi = limits.y_top - 0.5 * (1.0 - fraction) * span;
  if (request.min_um || request.max_um) {
    y_lo = request.min_um.value_or(y_lo);
    y_hi = request.max_um.value_or(y_hi);
    if (!(y_hi > y_lo))
      throw common::CommandError("bad_params", "max_um must be greater than min_um");
    if (y_lo < limits.y_bottom - 1e-9 || y_hi > limits.y_top + 1e-9) {
      throw common::CommandError("out_of_range", "reference [" + std::to_string(y_lo) + ", " +
                                                     std::to_string(y_hi) +
                                                     "] um is beyond the actuator range [" +
                                                     std::to_string(limits.y_bottom) + ", " +
                                                     std::to_string(limits.y_top) + "] um");
    }
  }
  spec.amplitude = 0.5 * (y_hi - y_lo);
  spec.offset = 0.5 * (y_hi + y_lo);
  spec.phase_rad = -M_PI / 2.0;  // start at the bottom of the range, rising
  spec.duration_s = duration;
  spec.rise_s = request.rise_s;

  TrackReference r;
  try {
    r.signal = sim::make_signal_generator(spec);
  } catch (const std::exception& e) {
    throw common::CommandError("bad_params", e.what());
  }
  const double dt = 1.0 / limits.rate_hz;
  r.samples = static_cast<std::uint64_t>(std::llround(duration / dt));
  const auto one_period = static_cast<std::uint64_t>(std::llround(1.0 / spec.frequency_hz / dt));
  r.unscored = r.samples >= 2 * one_period ? one_period : 0;
  r.min_um = y_lo;
  r.max_um = y_hi;
  if (spec.kind == sim::SignalKind::kSine || spec.kind == sim::SignalKind::kTriangle ||
      spec.kind == sim::SignalKind::kSawtooth) {
    r.frequency_hz = spec.frequency_hz;
  }
  r.header = {{"reference", ref_name},
              {"frequency_hz", spec.frequency_hz},
              {"duration_s", duration},
              {"min_um", y_lo},
              {"max_um", y_hi}};
  r.reply = {{"kind", ref_name}, {"min_um", y_lo}, {"max_um", y_hi}};
  if (spec.kind == sim::SignalKind::kStep) {
    r.header["rise_s"] = spec.rise_s;
    r.reply["rise_s"] = spec.rise_s;
  }
  return r;
}

TrackReference uploaded_reference(const Upload& upload, const ReferenceLimits& limits,
                                  double y_start, double approach_s,
                                  std::optional<std::size_t> learned_trials, double lead_in_max_s) {
  const double dt = 1.0 / limits.rate_hz;
  check_range(upload, limits.y_bottom, limits.y_top, "um", "reference");
  std::vector<double> traj = upload.resampled(dt);
  if (traj.size() < 2) {
    throw common::CommandError("bad_params", "reference upload '" + upload.name + "' lasts " +
                                                 significant(upload.duration_s(), 6) +
                                                 " s: shorter than two loop periods");
  }
  const double max_step = limits.slew_um_per_s * dt;
  check_slew(upload, traj, max_step, dt, limits.slew_um_per_s, "um", "reference");

  // The approach: a raised cosine from where the precondition left the output to the first
  // value, long enough that its steepest point moves at most half the slew limit; between
  // passes, from the trajectory's end, as long as the first.
  const auto approach_ticks = [&](double jump) {
    const double needed = M_PI / 2.0 * std::abs(jump) / (0.5 * limits.slew_um_per_s);
    return static_cast<std::size_t>(std::ceil(std::max(approach_s, needed) / dt));
  };
  std::size_t n_a = approach_ticks(traj.front() - y_start);
  if (learned_trials) n_a = std::max(n_a, approach_ticks(traj.front() - traj.back()));
  const auto [lo, hi] = std::minmax_element(traj.begin(), traj.end());
  TrackReference r;
  r.min_um = *lo;
  r.max_um = *hi;
  r.signature = signature_of(traj);
  r.content_hz = reversal_rate(traj, dt);
  const std::size_t resampled = traj.size();
  const std::size_t pass = n_a + resampled;
  std::vector<double> first = approach(y_start, traj.front(), n_a);
  first.insert(first.end(), traj.begin(), traj.end());
  double passes = 1.0;
  if (learned_trials) {
    r.lead_in_passes = periods_filling(lead_in_max_s, limits.rate_hz / static_cast<double>(pass));
    passes = learning_periods(*learned_trials, limits.rate_hz / static_cast<double>(pass)) +
             static_cast<double>(r.lead_in_passes - 1);
    std::vector<double> later = approach(traj.back(), traj.front(), n_a);
    later.insert(later.end(), traj.begin(), traj.end());
    traj = {};
    r.pass_samples = pass;
    r.pass_approach = n_a;
    r.frequency_hz = limits.rate_hz / static_cast<double>(pass);
    r.samples = static_cast<std::uint64_t>(passes) * pass;
    r.unscored = r.lead_in_passes * pass;
    r.signal = std::make_unique<RepeatedPasses>(std::move(first), std::move(later),
                                                static_cast<std::size_t>(passes), dt);
  } else {
    traj = {};
    r.samples = pass;
    r.unscored = n_a;
    r.signal = sim::make_uniform_signal(std::move(first), dt);
  }
  r.header = {{"reference", "upload"},
              {"source", upload.source},
              {"upload_samples", upload.values.size()},
              {"resampled_samples", resampled},
              {"approach_s", static_cast<double>(n_a) * dt},
              {"duration_s", static_cast<double>(r.samples) * dt},
              {"min_um", r.min_um},
              {"max_um", r.max_um},
              {"signature", r.signature}};
  r.reply = {{"kind", "upload"},
             {"source", upload.source},
             {"samples", upload.values.size()},
             {"resampled_samples", resampled},
             {"approach_s", static_cast<double>(n_a) * dt},
             {"min_um", r.min_um},
             {"max_um", r.max_um},
             {"signature", r.signature}};
  if (learned_trials) {
    r.header["passes"] = passes;
    r.reply["pass_samples"] = pass;
  }
  return r;
}

double learning_periods(std::size_t trials, double frequency_hz) {
  // Trial 0's drive plays twice (trial 1 measures the bench's floor) before N learned trials.
  const std::size_t played = trials > 0 ? trials + 1 : trials;
  const double allowance =
      std::ceil(kUpdateAllowanceS * frequency_hz) * static_cast<double>(played + 1);
  return static_cast<double>(played + 2) + allowance;
}

std::size_t periods_filling(double seconds, double frequency_hz) {
  return std::max<std::size_t>(1,
                               static_cast<std::size_t>(std::ceil(seconds * frequency_hz - 1e-9)));
}

std::vector<double> checked_drive(const Upload& upload, double u_min, double u_max,
                                  double slew_v_per_s, double dt_s) {
  check_range(upload, u_min, u_max, "V", "drive");
  std::vector<double> drive = upload.resampled(dt_s);
  if (drive.size() < 2) {
    throw common::CommandError("bad_params", "drive upload '" + upload.name + "' lasts " +
                                                 significant(upload.duration_s(), 6) +
                                                 " s: shorter than two loop periods");
  }
  check_slew(upload, drive, slew_v_per_s * dt_s, dt_s, slew_v_per_s, "V", "drive");
  return drive;
}

}  // namespace hystbench::daemon::details
