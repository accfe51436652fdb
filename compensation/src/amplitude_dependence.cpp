#include "hystbench/compensation/amplitude_dependence.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "details/parallel_tasks.hpp"

namespace hystbench::compensation {

namespace {

using cd = std::complex<double>;

std::size_t first_scored(const PeriodicRecord& r) { return r.periods >= 2 ? r.period : 0; }

std::string record_name(std::size_t i) { return "record " + std::to_string(i + 1); }

void check_alike(const std::vector<PeriodicRecord>& records) {
  if (records.size() < 2) throw std::invalid_argument("amplitude schedule: two records or more");
  const PeriodicRecord& a = records.front();
  if (a.u.empty()) throw std::invalid_argument("amplitude schedule: " + record_name(0) + " empty");
  for (std::size_t i = 1; i < records.size(); ++i) {
    const PeriodicRecord& b = records[i];
    if (b.u.empty() || b.u[0].rows() != a.u[0].rows() || b.y[0].rows() != a.y[0].rows()) {
      throw std::invalid_argument("amplitude schedule: " + record_name(i) +
                                  " has other inputs or " + "outputs than " + record_name(0));
    }
    if (std::abs(b.dt - a.dt) > 1e-9 * a.dt) {
      throw std::invalid_argument("amplitude schedule: " + record_name(i) +
                                  " has another sample period than " + record_name(0));
    }
  }
}

// One record of every realization of `records` but `skip`.
PeriodicRecord pooled(const std::vector<PeriodicRecord>& records, std::size_t skip) {
  PeriodicRecord p;
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (i == skip) continue;
    const PeriodicRecord& r = records[i];
    p.period = r.period;
    p.periods = r.periods;
    p.dt = r.dt;
    p.u.insert(p.u.end(), r.u.begin(), r.u.end());
    p.y.insert(p.y.end(), r.y.begin(), r.y.end());
  }
  return p;
}

// The lightly damped modes of a linear block: frequency, damping and peak |G| (the pair's own
// term at its frequency, Frobenius norm).
struct Mode {
  double f = 0.0, zeta = 0.0, peak = 0.0;
};

std::vector<Mode> modes_of(const MimoLinearModel& g, double dt, double f_max) {
  std::vector<Mode> modes;
  std::size_t term = 1;  // terms: D first, then per pole one (real) or two (pair)
  for (const cd p : g.poles()) {
    if (p.imag() <= 0.0) {
      ++term;
      continue;
    }
    const cd s = std::log(p) / dt;
    const Eigen::MatrixXcd r =
        g.terms()[term].cast<cd>() + cd(0.0, 1.0) * g.terms()[term + 1].cast<cd>();
    term += 2;
    Mode m{std::abs(s) / (2.0 * std::numbers::pi), -s.real() / std::abs(s), 0.0};
    m.peak = r.norm() / std::max(1.0 - std::abs(p), 1e-12);
    if (m.f <= f_max && m.zeta < 0.2) modes.push_back(m);
  }
  return modes;
}

}  // namespace

double periodic_amplitude(const PeriodicRecord& record) {
  double var = 0.0;
  std::size_t n = 0;
  for (const auto& u : record.u) {
    const std::size_t from = first_scored(record);
    const Eigen::MatrixXd steady = u.rightCols(u.cols() - static_cast<Eigen::Index>(from));
    const double a = record_amplitude(steady);
    var += a * a;
    ++n;
  }
  return n > 0 ? std::sqrt(var / static_cast<double>(n)) : 0.0;
}

std::vector<std::vector<std::size_t>> amplitude_groups(const PeriodicRecord& record) {
  const std::size_t n = record.u.size();
  std::vector<double> a(n);
  for (std::size_t r = 0; r < n; ++r) a[r] = periodic_amplitude(realizations_of(record, {r}));
  std::vector<std::size_t> by(n);
  std::iota(by.begin(), by.end(), std::size_t{0});
  std::stable_sort(by.begin(), by.end(), [&](std::size_t x, std::size_t y) { return a[x] < a[y]; });
  std::vector<std::vector<std::size_t>> groups;
  for (std::size_t k = 0; k < n; ++k) {
    if (k == 0 || a[by[k]] > (1.0 + kAmplitudeGroupGap) * a[by[k - 1]]) groups.emplace_back();
    groups.back().push_back(by[k]);
  }
  for (auto& g : groups) std::sort(g.begin(), g.end());
  return groups;
}

PeriodicRecord realizations_of(const PeriodicRecord& record,
                               const std::vector<std::size_t>& realizations) {
  PeriodicRecord r;
  r.period = record.period;
  r.periods = record.periods;
  r.dt = record.dt;
  for (const std::size_t i : realizations) {
    r.u.push_back(record.u.at(i));
    r.y.push_back(record.y.at(i));
  }
  return r;
}

double simulation_rms(const std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)>& simulate,
                      const PeriodicRecord& record) {
  double sum2 = 0.0;
  double count = 0.0;
  for (std::size_t r = 0; r < record.u.size(); ++r) {
    const Eigen::MatrixXd y = simulate(record.u[r]);
    const auto from = static_cast<Eigen::Index>(first_scored(record));
    const Eigen::MatrixXd e = record.y[r].rightCols(y.cols() - from) - y.rightCols(y.cols() - from);
    sum2 += e.squaredNorm();
    count += static_cast<double>(e.size());
  }
  return count > 0.0 ? std::sqrt(sum2 / count) : 0.0;
}

AmplitudeFit fit_amplitude_schedule(const std::vector<PeriodicRecord>& records,
                                    const AmplitudeFitOptions& options) {
  check_alike(records);
  const std::size_t n = records.size();
  std::vector<double> amplitude(n);
  for (std::size_t i = 0; i < n; ++i) amplitude[i] = periodic_amplitude(records[i]);
  AmplitudeFit fit;
  fit.order.resize(n);
  std::iota(fit.order.begin(), fit.order.end(), std::size_t{0});
  std::stable_sort(fit.order.begin(), fit.order.end(),
                   [&](std::size_t a, std::size_t b) { return amplitude[a] < amplitude[b]; });
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = fit.order[k];
    if (!(amplitude[i] > 0.0)) {
      throw std::invalid_argument("amplitude schedule: " + record_name(i) +
                                  "'s inputs are constant");
    }
    if (k > 0 && amplitude[i] < (1.0 + kDistinctAmplitude) * fit.amplitudes.back()) {
      throw std::invalid_argument(
          "amplitude schedule: " + record_name(fit.order[k - 1]) + " and " + record_name(i) +
          " are at one amplitude (" + std::to_string(fit.amplitudes.back()) + " and " +
          std::to_string(amplitude[i]) + "): join them as realizations of one record");
    }
    fit.amplitudes.push_back(amplitude[i]);
  }
  // The records' fits are independent: one per core.
  fit.local.resize(n);
  details::SharedProgress shared(n, options.progress);
  details::run_parallel(n, [&](std::size_t k) {
    HammersteinFitOptions o = options.local;
    const std::string at = "amplitude " + std::to_string(k + 1) + "/" + std::to_string(n) + ": ";
    o.linear.progress = [&, k](double f, const std::string& what) { shared(k, f, at + what); };
    fit.local[k] = identify_mimo_hammerstein(records[fit.order[k]], o);
  });
  std::vector<HammersteinMimoModel> local;
  for (const auto& l : fit.local) local.push_back(l.model);
  fit.model.emplace(fit.amplitudes, std::move(local), options.window_s);
  for (std::size_t k = 0; k < n; ++k) {
    const PeriodicRecord& record = records[fit.order[k]];
    fit.schedule_rms.push_back(
        simulation_rms([&](const Eigen::MatrixXd& u) { return fit.model->simulate(u); }, record));
    const AmplitudeScheduledMimoModel others = fit.model->without(k);
    fit.left_out_rms.push_back(
        simulation_rms([&](const Eigen::MatrixXd& u) { return others.simulate(u); }, record));
  }
  if (options.progress) options.progress(1.0, "done");
  return fit;
}

namespace {

// How each entry's response changes from the lowest amplitude's model to the highest's over the
// excited bins of s, largest change first.
std::vector<EntryChange> entry_changes(const MimoLinearModel& lo, const MimoLinearModel& hi,
                                       const PeriodicSpectra& s) {
  const double f_of_bin = 1.0 / (static_cast<double>(s.period) * s.dt);
  const auto p = static_cast<Eigen::Index>(hi.outputs());
  const auto m = static_cast<Eigen::Index>(hi.inputs());
  Eigen::MatrixXd diff2 = Eigen::MatrixXd::Zero(p, m), ref2 = diff2, worst = diff2, at = diff2;
  for (std::size_t k = 0; k < s.bins.size(); ++k) {
    const Eigen::MatrixXcd gh = hi.response(s.z(k)), gl = lo.response(s.z(k));
    for (Eigen::Index i = 0; i < p; ++i) {
      for (Eigen::Index j = 0; j < m; ++j) {
        const double e = std::abs(gh(i, j) - gl(i, j));
        diff2(i, j) += e * e;
        ref2(i, j) += std::norm(gh(i, j));
        if (e > worst(i, j)) {
          worst(i, j) = e;
          at(i, j) = static_cast<double>(s.bins[k]) * f_of_bin;
        }
      }
    }
  }
  std::vector<EntryChange> entries;
  for (Eigen::Index i = 0; i < p; ++i) {
    for (Eigen::Index j = 0; j < m; ++j) {
      entries.push_back({static_cast<std::size_t>(i), static_cast<std::size_t>(j),
                         std::sqrt(diff2(i, j) / std::max(ref2(i, j), 1e-300)), at(i, j)});
    }
  }
  std::sort(entries.begin(), entries.end(),
            [](const EntryChange& a, const EntryChange& b) { return a.change > b.change; });
  return entries;
}

// The dominant modes of the highest amplitude's model, each matched with the nearest in
// frequency of every amplitude's model (among its modes of at least a tenth of the peak, where
// there are).
std::vector<ModeShift> mode_shifts(const AmplitudeFit& fit, double dt, double f_max) {
  constexpr std::size_t kModes = 5;
  const std::size_t n = fit.local.size();
  std::vector<std::vector<Mode>> per(n);
  for (std::size_t k = 0; k < n; ++k) per[k] = modes_of(fit.local[k].model.dynamics(), dt, f_max);
  std::vector<Mode> top = per.back();
  std::sort(top.begin(), top.end(), [](const Mode& a, const Mode& b) { return a.peak > b.peak; });
  // Dominant: within 40 dB of the strongest (the rest are the fit's own, below the noise).
  if (!top.empty()) {
    const double strongest = top.front().peak;
    std::erase_if(top, [&](const Mode& m) { return m.peak < 0.01 * strongest; });
  }
  if (top.size() > kModes) top.resize(kModes);
  std::vector<ModeShift> shifts;
  for (const Mode& ref : top) {
    ModeShift shift;
    for (std::size_t k = 0; k < n; ++k) {
      const Mode* best = nullptr;
      for (const bool strong : {true, false}) {
        for (const Mode& c : per[k]) {
          if (strong && c.peak < 0.1 * ref.peak) continue;
          if (best == nullptr || std::abs(c.f - ref.f) < std::abs(best->f - ref.f)) best = &c;
        }
        if (best != nullptr) break;
      }
      const Mode mk = best != nullptr ? *best : ref;
      shift.frequency_hz.push_back(mk.f);
      shift.damping.push_back(mk.zeta);
      shift.peak.push_back(mk.peak);
    }
    shift.shift_percent = 100.0 * (shift.frequency_hz.back() / shift.frequency_hz.front() - 1.0);
    shift.peak_ratio = shift.peak.back() / std::max(shift.peak.front(), 1e-300);
    shifts.push_back(std::move(shift));
  }
  return shifts;
}

}  // namespace

AmplitudeDiagnosis diagnose_amplitude_dependence(const std::vector<PeriodicRecord>& records,
                                                 const AmplitudeFit& fit,
                                                 const HammersteinFitOptions& options,
                                                 const FitProgress& progress) {
  check_alike(records);
  if (!fit.model || fit.order.size() != records.size()) {
    throw std::invalid_argument("amplitude diagnosis: the fit is of other records");
  }
  for (const auto& r : records) {
    if (r.period != records.front().period || r.periods != records.front().periods) {
      throw std::invalid_argument(
          "amplitude diagnosis: records of one period length and count (to pool them)");
    }
  }
  const std::size_t n = records.size();
  std::vector<PeriodicRecord> sorted;
  for (const std::size_t i : fit.order) sorted.push_back(records[i]);
  AmplitudeDiagnosis d;
  d.amplitudes = fit.amplitudes;
  // The baselines' fits are independent: one per core.
  std::vector<HammersteinFitResult> baselines(n);
  details::SharedProgress shared(n, progress);
  details::run_parallel(n, [&](std::size_t k) {
    HammersteinFitOptions o = options;
    const std::string at = "amplitude " + std::to_string(k + 1) + " left out: ";
    o.linear.progress = [&, k](double f, const std::string& what) { shared(k, f, at + what); };
    baselines[k] = identify_mimo_hammerstein(pooled(sorted, k), o);
  });
  double log_gain = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const HammersteinFitResult& baseline = baselines[k];
    AmplitudeLeftOut l;
    l.amplitude = fit.amplitudes[k];
    l.baseline_order = baseline.linear.order;
    l.baseline_rms = simulation_rms(
        [&](const Eigen::MatrixXd& u) { return baseline.model.simulate(u); }, sorted[k]);
    l.extended_rms = fit.left_out_rms[k];
    l.gain = l.baseline_rms / std::max(l.extended_rms, 1e-300);
    log_gain += std::log(l.gain);
    d.left_out.push_back(l);
  }
  d.gain = std::exp(log_gain / static_cast<double>(n));
  d.named = d.gain >= kAmplitudeNamingGain;
  const PeriodicSpectra s = periodic_spectra(sorted.back());
  d.entries =
      entry_changes(fit.local.front().model.dynamics(), fit.local.back().model.dynamics(), s);
  const double f_max = static_cast<double>(s.bins.back()) / (static_cast<double>(s.period) * s.dt);
  d.modes = mode_shifts(fit, s.dt, f_max);
  if (progress) progress(1.0, "done");
  return d;
}

}  // namespace hystbench::compensation
