#include "hystbench/compensation/iterative_learning.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <unsupported/Eigen/FFT>
#include <utility>

#include "details/diagnosis_signals.hpp"

namespace hystbench::compensation {

namespace {

// The two sections of a fourth-order Butterworth low-pass: their quality factors.
constexpr std::array<double, 2> kButterworthQ = {0.54119610014619690, 1.30656296487637653};
// Q's default cut-off: this fraction of the sample rate, and this fraction of a modelled mode
// (below it the mode's gain and phase lag stay within what a learning gain of 1/2 converges
// through for a damping of 0.05 or more: at most 5x and 30 degrees at 0.9 of it, where Q passes
// half).
constexpr double kCutoffOfRate = 0.2;
constexpr double kCutoffOfMode = 0.9;
// ... and at most this harmonic of the trial's frequency: a slow trial's error above it is mostly
// the sensor's noise, which each trial would otherwise learn into the drive.
constexpr double kCutoffHarmonics = 300.0;
// ... but at least past the fifth harmonic (a loop's error is mostly its odd harmonics, and a fast
// trial cut below its fifth learns only part of it), within this fraction of the sample rate.
constexpr double kCutoffFloorHarmonic = 5.5;
constexpr double kCutoffFloorOfRate = 0.3;
// The bench's delay is searched up to this many samples beyond the model's, and taken from a
// pair of trials whose changes correlate at least this well at it.
constexpr std::size_t kDelaySearch = 50;
constexpr double kDelayClear = 0.5;
// Each pair of trials moves the drift's estimate this far toward what it showed; estimated over
// trials of at least kDriftSeconds.
constexpr double kDriftBlend = 0.5;
constexpr double kDriftSeconds = 0.5;
// The drive the learning goes on from reaches at most this fraction of the drive's span beyond
// its limits (a reference the actuator cannot reach there would otherwise wind it up without
// bound; within it the first trials' overshoot unwinds without a cut).
constexpr double kBeyondLimits = 0.2;
// Of what the model's slope predicts a trial's change at its end does to the next trial's start,
// the share taken off the error that wraps there. With the whole of it a trial's start converges
// as the rest does where the slope is right, but at 0.81 a trial where the bench answers with half
// of it (near a turning point, through a mode the model lacks); with none at 0.71, swinging from
// trial to trial. Half: 0.5 and 0.75.
constexpr double kWrapShare = 0.5;
// A fast trial (the fifth-harmonic floor above sets Q's cut-off) learns its harmonics above Q
// too, up to this fraction of the sample rate, once the bench's delay is the median of this many
// trial pairs: each through the mode (the model's, else the bench's timed one in the options)
// and that delay, exactly at its frequency (a trial holds whole harmonics). Not where they leave
// less than this gain (an inverse would amplify the noise there). A trial pair's changes do not
// show the bench's answer there: a hysteresis answers the fundamental's change with every
// harmonic, so a change above Q is only partly the drive's (docs/measurements.md, "Learning a
// repeated reference"; IterativeLearning.AFastTrialLearnsAboveQThroughTheTimedMode).
constexpr double kHighBandOfRate = 0.45;
constexpr double kHighBandMinGain = 0.25;
constexpr std::size_t kHighBandDelayPairs = 3;
// The measured response checked in place: the lag at which the output's change between two
// trials best follows the drive's change through the response, searched this far each way
// [samples], the median over this many pairs, applied where it is at least kResidualMin (a
// response measured on this bench shows none; one carried in a model from another, a delay
// switched on or a slower link since, shows what it lacks).
constexpr std::size_t kResidualSearch = 8;
constexpr std::size_t kResidualPairs = 3;
constexpr double kResidualMin = 0.5;

// The lag in [from, to] [samples] at which the output's change best follows the drive's (cu and
// cy: both over a trial pair, through Q), the two differenced (what changes slowly, creep
// answering late or a drift, would stretch it) and refined between samples; none where the peak
// is not clear (below kDelayClear of their norms: a change that mostly is not the drive's) or
// sits at the search's edge (beyond it).
std::optional<double> clearest_lag(const std::vector<double>& cu, const std::vector<double>& cy,
                                   std::ptrdiff_t from, std::ptrdiff_t to) {
  const std::size_t n = cu.size();
  std::vector<double> du(n), dy(n);
  double uu = 0.0, yy = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t p = (j + n - 1) % n;
    du[j] = cu[j] - cu[p];
    dy[j] = cy[j] - cy[p];
    uu += du[j] * du[j];
    yy += dy[j] * dy[j];
  }
  if (!(uu > 0.0 && yy > 0.0) || to <= from) return std::nullopt;
  const auto span = static_cast<std::ptrdiff_t>(n);
  std::vector<double> corr(static_cast<std::size_t>(to - from + 1), 0.0);
  std::size_t best = 0;
  for (std::size_t i = 0; i < corr.size(); ++i) {
    const std::ptrdiff_t d = from + static_cast<std::ptrdiff_t>(i);
    for (std::size_t j = 0; j < n; ++j) {
      corr[i] += dy[static_cast<std::size_t>(((static_cast<std::ptrdiff_t>(j) + d) % span + span) %
                                             span)] *
                 du[j];
    }
    if (corr[i] > corr[best]) best = i;
  }
  if (best == 0 || best + 1 == corr.size() || corr[best] < kDelayClear * std::sqrt(uu * yy)) {
    return std::nullopt;
  }
  const double c0 = corr[best - 1], c1 = corr[best], c2 = corr[best + 1];
  const double curvature = c0 - 2.0 * c1 + c2;
  const double vertex = curvature < 0.0 ? 0.5 * (c0 - c2) / curvature : 0.0;
  return static_cast<double>(from + static_cast<std::ptrdiff_t>(best)) +
         std::clamp(vertex, -0.5, 0.5);
}
// ... and once the error Q leaves out is at least this share of what it passes (rms): below it,
// the error there is mostly what the fundamental's changes make of it, which the next trial's
// change remakes, and learning it slows the learning (docs/measurements.md, "Learning a repeated
// reference": the fast trials with every effect on).
constexpr double kHighBandShare = 0.5;
// The circular run of a section starts this many of its slowest time constants early.
constexpr double kWarmupTimeConstants = 20.0;

// A low-pass biquad at f0 / fs with quality q (bilinear, exact at f0): b0 b1 b2 a1 a2.
std::array<double, 5> low_pass_section(double f0_over_fs, double q) {
  const double w0 = 2.0 * std::numbers::pi * f0_over_fs;
  const double alpha = std::sin(w0) / (2.0 * q);
  const double c = std::cos(w0);
  const double a0 = 1.0 + alpha;
  const double b0 = 0.5 * (1.0 - c) / a0;
  return {b0, 2.0 * b0, b0, -2.0 * c / a0, (1.0 - alpha) / a0};
}

}  // namespace

IterativeLearning::IterativeLearning(const ActuatorModel& model, std::size_t period_samples,
                                     LearningOptions options)
    : model_(model), period_(period_samples), o_(std::move(options)) {
  if (!model_.valid()) throw std::invalid_argument("iterative learning needs a model");
  if (period_ < 4) throw std::invalid_argument("iterative learning needs a trial of 4 samples");
  if (!(o_.dt > 0.0)) throw std::invalid_argument("iterative learning needs a sample period > 0");
  if (!(o_.u_min < o_.u_max) || !(o_.max_step > 0.0)) {
    throw std::invalid_argument("iterative learning needs u_min < u_max and max_step > 0");
  }
  const double fs = 1.0 / o_.dt;
  const double trial_hz =
      std::max(fs / static_cast<double>(period_), std::max(o_.fundamental_hz, 0.0));
  cutoff_hz_ =
      o_.cutoff_hz > 0.0 ? o_.cutoff_hz : std::min(kCutoffOfRate * fs, kCutoffHarmonics * trial_hz);
  if (o_.cutoff_hz <= 0.0) {
    cutoff_hz_ =
        std::max(cutoff_hz_, std::min(kCutoffFloorHarmonic * trial_hz, kCutoffFloorOfRate * fs));
  }
  advance_samples_ = model_delay_samples_ = model_.delay_s() / o_.dt;
  fast_trial_ = kCutoffFloorHarmonic * trial_hz > kCutoffOfRate * fs;
  const bool measured = o_.measured_plant.has_value();
  if (measured) {
    const MeasuredLearningPlant& m = *o_.measured_plant;
    if (m.frequency_hz.empty() || m.frequency_hz.size() != m.response.size() ||
        m.stage_gain.size() != m.response.size()) {
      throw std::invalid_argument("iterative learning: the measured plant needs lines");
    }
  }
  // A mode the learning does not invert holds Q below it; the measured plant inverts it.
  if (const auto& d = model_.dynamics(); d && o_.cutoff_hz <= 0.0 && !measured) {
    cutoff_hz_ = std::min(cutoff_hz_, kCutoffOfMode * d->natural_frequency_hz);
  }
  if (const auto& d = model_.dynamics() ? model_.dynamics() : o_.bench_mode;
      d && fast_trial_ && o_.cutoff_hz <= 0.0 && !measured) {
    mode_.emplace(*d, o_.dt);
  }
  cutoff_hz_ = std::min(cutoff_hz_, 0.45 * fs);
  for (const double q : kButterworthQ) sections_.push_back(low_pass_section(cutoff_hz_ / fs, q));
  const double slowest_s = 2.0 * kButterworthQ[1] / (2.0 * std::numbers::pi * cutoff_hz_);
  warmup_periods_ = static_cast<std::size_t>(
      std::ceil(kWarmupTimeConstants * slowest_s / (o_.dt * static_cast<double>(period_))));
  warmup_periods_ = std::max<std::size_t>(warmup_periods_, 1);
  model_.set_delay(0.0);
  model_.set_dynamics(std::nullopt);
  model_.configure(o_.dt);
  slope_.assign(period_, 0.0);
  work_.assign(period_, 0.0);
  shifted_.assign(period_, 0.0);
}

void IterativeLearning::low_pass(std::vector<double>& x) {
  const std::size_t n = x.size();
  // Each section starts at the trial's mean, at rest (a low-pass keeps the mean), then goes round
  // until its state is periodic.
  double mean = 0.0;
  for (const double v : x) mean += v;
  mean /= static_cast<double>(n);
  for (int pass = 0; pass < 2; ++pass) {  // forward, then backward: zero phase
    for (const auto& s : sections_) {
      double x1 = mean, x2 = mean, y1 = mean, y2 = mean;
      for (std::size_t r = 0; r <= warmup_periods_; ++r) {
        const bool keep = r == warmup_periods_;
        for (std::size_t j = 0; j < n; ++j) {
          const double in = x[j];
          const double out = s[0] * in + s[1] * x1 + s[2] * x2 - s[3] * y1 - s[4] * y2;
          x2 = x1, x1 = in, y2 = y1, y1 = out;
          if (keep) shifted_[j] = out;
        }
      }
      std::copy(shifted_.begin(), shifted_.end(), x.begin());
    }
    std::reverse(x.begin(), x.end());
  }
}

void IterativeLearning::local_slope(std::span<const double> drive) {
  const std::size_t n = period_;
  // The model's static output along the drive, its state periodic after a first pass.
  model_.reset(drive[n - 1]);
  std::vector<double>& y = work_;
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t j = 0; j < n; ++j) y[j] = model_.step(drive[j]);
  }
  // Least-squares slope of dy on du over a window around each sample, circular.
  const std::size_t w = std::max<std::size_t>(2, n / 100);
  double sum_dy = 0.0, sum_du = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t p = (j + n - 1) % n;
    sum_dy += std::abs(y[j] - y[p]);
    sum_du += std::abs(drive[j] - drive[p]);
  }
  double mean = sum_du > 0.0 ? sum_dy / sum_du : 0.0;
  if (!(mean > 0.0)) {
    // A constant drive: the slope of the model's range.
    ActuatorModel probe = model_;
    probe.reset(model_.input_min);
    const double span = model_.input_max - model_.input_min;
    mean =
        span > 0.0
            ? std::abs(probe.peek_static(model_.input_max) - probe.peek_static(model_.input_min)) /
                  span
            : 1.0;
  }
  // Running sums over the window [j - w, j + w] around the trial.
  const auto du = [&](std::size_t c) { return drive[c] - drive[(c + n - 1) % n]; };
  const auto dy = [&](std::size_t c) { return y[c] - y[(c + n - 1) % n]; };
  double uy = 0.0, uu = 0.0;
  for (std::size_t i = 0; i <= 2 * w; ++i) {
    const std::size_t c = (n + i - w % n) % n;
    uy += du(c) * dy(c);
    uu += du(c) * du(c);
  }
  for (std::size_t j = 0; j < n; ++j) {
    const double s = uu > 1e-300 ? uy / uu : mean;
    slope_[j] = std::clamp(s, o_.min_slope * mean, o_.max_slope * mean);
    const std::size_t out = (j + n - w % n) % n, in = (j + w + 1) % n;
    uy += du(in) * dy(in) - du(out) * dy(out);
    uu += du(in) * du(in) - du(out) * du(out);
  }
}

void IterativeLearning::pair_changes(std::span<const double> drive, std::span<const double> error,
                                     std::vector<double>& cu, std::vector<double>& cy) {
  const std::size_t n = period_;
  cu.resize(n);
  cy.resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    cu[j] = (drive[j] - last_drive_[j]) * slope_[j];
    cy[j] = last_error_[j] - error[j];
  }
  low_pass(cu);
  low_pass(cy);
}

void IterativeLearning::measure_delay(std::span<const double> drive,
                                      std::span<const double> error) {
  const std::size_t n = period_;
  // The drive's change between the trials through the slope along the one before (slope_ is
  // still its), and the output's change: dy(j + d) = du(j) at the bench's delay d. Both are
  // differenced: what changes slowly (creep answering the drive late, drift) would stretch the
  // delay found, and is not what the preview has to meet.
  // The output's change goes through Q first, as the drive's did: above it is the sensor's noise.
  std::vector<double> cu, cy;
  pair_changes(drive, error, cu, cy);
  const std::size_t lags =
      std::min(n / 4, static_cast<std::size_t>(std::ceil(model_delay_samples_)) + kDelaySearch);
  const std::optional<double> lag = clearest_lag(cu, cy, 0, static_cast<std::ptrdiff_t>(lags));
  if (!lag) return;
  delays_.push_back(*lag);
  // Their median: a pair that one slow or noisy change misled does not move it.
  std::vector<double> sorted = delays_;
  const std::size_t m = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(m), sorted.end());
  advance_samples_ = sorted[m];
  if (sorted.size() % 2 == 0) {
    advance_samples_ =
        0.5 * (advance_samples_ +
               *std::max_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(m)));
  }
}

std::vector<double> IterativeLearning::advanced_error(std::span<const double> error,
                                                      std::span<const double> drive,
                                                      const std::vector<double>& before) {
  const std::size_t n = period_;
  std::vector<double> c(error.begin(), error.end());
  low_pass(c);
  // The error d samples on answers the drive here: advance it (linear between samples).
  const double a = std::fmod(advance_samples_, static_cast<double>(n));
  const auto whole = static_cast<std::size_t>(std::floor(a));
  const double frac = a - std::floor(a);
  std::vector<double> e(n);
  for (std::size_t j = 0; j < n; ++j) {
    const double v0 = c[(j + whole) % n], v1 = c[(j + whole + 1) % n];
    e[j] = v0 + frac * (v1 - v0);
  }
  // Where the advanced error wraps round to the trial's start, it answered the drive the trial
  // before played there; the next trial's start answers this trial's drive. What this trial
  // changed there is taken off the error (kWrapShare of what the model's slope predicts), or each
  // change would be learned twice, a trial late, and the trial's start would swing from trial to
  // trial.
  if (before.size() == n) {
    for (std::size_t j = 0; j < n; ++j) e[j] -= wrapped_change(drive, before, j);
  }
  return e;
}

double IterativeLearning::wrapped_change(std::span<const double> drive,
                                         const std::vector<double>& before, std::size_t j) const {
  const double a = std::fmod(advance_samples_, static_cast<double>(period_));
  const double wraps =
      std::clamp(static_cast<double>(j) + a - static_cast<double>(period_ - 1), 0.0, 1.0);
  return wraps > 0.0 ? kWrapShare * wraps * slope_[j] * (drive[j] - before[j]) : 0.0;
}

void IterativeLearning::take_off_wrapped_change(std::span<const double> drive,
                                                const std::vector<double>& before,
                                                std::vector<double>& error) const {
  if (before.size() != period_) return;
  const std::size_t n = period_;
  const double a = std::fmod(advance_samples_, static_cast<double>(n));
  const auto whole = static_cast<std::size_t>(std::floor(a));
  const double frac = a - std::floor(a);
  for (std::size_t j = 0; j < n; ++j) {
    const double change = wrapped_change(drive, before, j);
    if (change == 0.0) continue;
    error[(j + whole) % n] -= (1.0 - frac) * change;
    error[(j + whole + 1) % n] -= frac * change;
  }
}

std::complex<double> IterativeLearning::mode_response(double w) const {
  // y(k) = [1 0] s(k), s(k) = Phi s(k-1) + Gam x(k): Y / X = [1 0] (I - Phi / z)^-1 Gam.
  const std::complex<double> zi = std::polar(1.0, -w);
  const auto& m = *mode_;
  const std::complex<double> a = 1.0 - m.phi(0, 0) * zi, b = -m.phi(0, 1) * zi;
  const std::complex<double> c = -m.phi(1, 0) * zi, d = 1.0 - m.phi(1, 1) * zi;
  return (d * m.gam(0) - b * m.gam(1)) / (a * d - b * c);
}

std::complex<double> IterativeLearning::harmonic(std::span<const double> x, std::size_t h) const {
  const double w = 2.0 * std::numbers::pi * static_cast<double>(h) / static_cast<double>(period_);
  std::complex<double> sum = 0.0;
  for (std::size_t j = 0; j < period_; ++j)
    sum += x[j] * std::polar(1.0, -w * static_cast<double>(j));
  return sum;
}

std::complex<double> IterativeLearning::measured_response(double f_hz, double& stage_gain) const {
  return measured_lines(f_hz, stage_gain) *
         std::polar(1.0, -2.0 * std::numbers::pi * f_hz * residual_delay_samples_ * o_.dt);
}

std::complex<double> IterativeLearning::measured_lines(double f_hz, double& stage_gain) const {
  const MeasuredLearningPlant& m = *o_.measured_plant;
  const std::vector<double>& f = m.frequency_hz;
  stage_gain = 0.0;
  if (f_hz > f.back()) return 0.0;
  if (f_hz <= f.front()) {
    stage_gain = m.stage_gain.front();
    return m.response.front();
  }
  const auto hi = static_cast<std::size_t>(std::upper_bound(f.begin(), f.end(), f_hz) - f.begin());
  const std::size_t lo = hi - 1;
  if (hi >= f.size()) {
    stage_gain = m.stage_gain.back();
    return m.response.back();
  }
  // Linear in log frequency, of the log magnitude and of the phase step between the lines.
  const double w = std::log(f_hz / f[lo]) / std::log(f[hi] / f[lo]);
  stage_gain = (1.0 - w) * m.stage_gain[lo] + w * m.stage_gain[hi];
  const std::complex<double> a = m.response[lo], b = m.response[hi];
  const double mag = std::exp((1.0 - w) * std::log(std::abs(a)) + w * std::log(std::abs(b)));
  const double phase =
      std::arg(a) + w * std::remainder(std::arg(b) - std::arg(a), 2.0 * std::numbers::pi);
  return std::polar(mag, phase);
}

void IterativeLearning::measure_residual_delay(std::span<const double> drive,
                                               std::span<const double> error) {
  const std::size_t n = period_;
  const std::size_t search = std::min(kResidualSearch, n / 4);
  if (search < 2) return;
  // The drive's change through the slope along the trial before and the measured response,
  // and the output's change, both through Q (as for the delay).
  std::vector<double> cu, cy;
  pair_changes(drive, error, cu, cy);
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, cu);
  const double fs = 1.0 / o_.dt;
  for (std::size_t h = 1; h <= n / 2; ++h) {
    double stage = 0.0;
    const double f = static_cast<double>(h) * fs / static_cast<double>(n);
    spectrum[h] *= measured_response(f, stage);
    if (h < n - h) spectrum[n - h] = std::conj(spectrum[h]);
  }
  fft.inv(cu, spectrum);
  const auto k = static_cast<std::ptrdiff_t>(search);
  const std::optional<double> lag = clearest_lag(cu, cy, -k, k);
  if (!lag) return;
  residual_delays_.push_back(*lag);
  if (residual_delays_.size() < kResidualPairs) return;
  // Their median, once there are enough of them; the response is moved by it where it is
  // kResidualMin or more (what the measured response holds is then not this bench's delay).
  // Measured on the response as moved so far: what it still lacks adds to what it was moved by.
  const double lacking = details::median(residual_delays_, 0.0);
  if (std::abs(lacking) >= kResidualMin) {
    residual_delay_samples_ += lacking;
    residual_delays_.clear();
  }
}

void IterativeLearning::through_measured_inverse(std::vector<double>& x) {
  const std::size_t n = x.size();
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, x);
  const double fs = 1.0 / o_.dt;
  measured_harmonics_ = measured_left_out_ = 0;
  for (std::size_t h = 0; h <= n / 2; ++h) {
    const double f = static_cast<double>(h) * fs / static_cast<double>(n);
    double stage = 0.0;
    const std::complex<double> p = measured_response(std::max(f, 1e-300), stage);
    std::complex<double> c = 0.0;
    if (stage >= kHighBandMinGain && std::abs(p) > 0.0) {
      c = spectrum[h] / p;
      if (h > 0) ++measured_harmonics_;
    } else if (h > 0 && f <= o_.measured_plant->frequency_hz.back()) {
      ++measured_left_out_;
    }
    if (h == 0) c = spectrum[0];  // the mean: the slope holds it (and the drift estimate)
    spectrum[h] = c;
    if (h > 0 && h < n - h) spectrum[n - h] = std::conj(c);
  }
  fft.inv(x, spectrum);
}

bool IterativeLearning::in_high_band(std::size_t h) const {
  const double fs = 1.0 / o_.dt;
  const double f = static_cast<double>(h) * fs / static_cast<double>(period_);
  return 2 * h < period_ && f > cutoff_hz_ && f <= kHighBandOfRate * fs;
}

void IterativeLearning::add_high_band(std::span<const double> error, double gain,
                                      std::vector<double>& correction) {
  const std::size_t n = period_;
  // What Q keeps out of the error.
  std::vector<double> high(error.begin(), error.end()), low(error.begin(), error.end());
  low_pass(low);
  double high2 = 0.0, low2 = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    high[j] -= low[j];
    high2 += high[j] * high[j];
    low2 += low[j] * low[j];
  }
  if (high2 < kHighBandShare * kHighBandShare * low2) return;
  ++high_band_updates_;
  std::vector<double> step(n, 0.0);
  for (std::size_t h = 1; 2 * h < n; ++h) {
    if (!in_high_band(h)) continue;
    // The bench's answer at this harmonic: the mode, then the delay.
    const double w = 2.0 * std::numbers::pi * static_cast<double>(h) / static_cast<double>(n);
    const std::complex<double> bench = mode_response(w) * std::polar(1.0, -w * advance_samples_);
    if (std::abs(bench) < kHighBandMinGain) continue;
    const std::complex<double> c =
        gain * harmonic(high, h) / bench * (2.0 / static_cast<double>(n));
    for (std::size_t j = 0; j < n; ++j) {
      step[j] += (c * std::polar(1.0, w * static_cast<double>(j))).real();
    }
  }
  for (std::size_t j = 0; j < n; ++j) correction[j] += step[j] / slope_[j];
}

void IterativeLearning::update(std::span<const double> drive, std::span<const double> error,
                               double gain, std::span<double> next) {
  const std::size_t n = period_;
  if (drive.size() != n || error.size() != n || next.size() != n) {
    throw std::invalid_argument("iterative learning: drive, error and next need one trial each");
  }
  if (updates_ > 0) {
    measure_delay(drive, error);
    if (o_.measured_plant) measure_residual_delay(drive, error);
  }
  // The drift over a trial: how far the trial's mean error moved beyond what the last correction's
  // mean should have moved it. Creep settling or a thermal drift moves the offset every trial,
  // which a correction of the last error alone trails by drift / gain.
  double mean_error = 0.0;
  for (const double v : error) mean_error += v;
  mean_error /= static_cast<double>(n);
  // Over a trial shorter than kDriftSeconds the drift is below what the mean shows of it beside
  // the loop's nonlinearity and a wrong model's gain on the last correction: not estimated.
  if (updates_ > 0 && static_cast<double>(n) * o_.dt >= kDriftSeconds) {
    drift_ += kDriftBlend * (mean_error - (last_mean_error_ - last_mean_step_) - drift_);
  }
  // The drive the trial before played: the one before this trial's start (the loop plays each
  // drive until the next is offered).
  std::vector<double> before(std::move(last_drive_));
  last_drive_.assign(drive.begin(), drive.end());
  last_error_.assign(error.begin(), error.end());
  local_slope(drive);
  std::vector<double> e;
  if (o_.measured_plant) {
    // The measured response holds the bench's delay and dynamics: the error through its inverse,
    // harmonic by harmonic, in place of the delay's advance.
    // Its start, though, answered the drive the trial before ended with: what this trial
    // changed there is taken off first, as where the error is advanced.
    e.assign(error.begin(), error.end());
    take_off_wrapped_change(drive, before, e);
    low_pass(e);
    through_measured_inverse(e);
  } else {
    e = advanced_error(error, drive, before);
  }
  std::vector<double> c(n);
  for (std::size_t j = 0; j < n; ++j) c[j] = (gain * e[j] + drift_) / slope_[j];
  last_mean_error_ = mean_error;
  last_mean_step_ = gain * mean_error + drift_;
  low_pass(c);
  if (mode_ && delays_.size() >= kHighBandDelayPairs) add_high_band(error, gain, c);
  // The drive the correction adds to: the one the last update made before the drive limits cut
  // it, where the trial played what that update offered. Cut sample by sample, a drive holds
  // harmonics above Q that no later correction reaches (and that a mode above Q lifts); kept out
  // of what is learned, the cut lasts only while the learned drive is beyond the limits (a
  // transient of the first trials, or a reference the actuator cannot reach there). Otherwise
  // the trial's drive, the first (the compensator's) through Q itself: above Q a correction
  // cannot reach it, and what the model put there (its harmonics through modes it does not
  // know, a wrap that was not periodic) would stay.
  std::vector<double> base;
  if (!unlimited_.empty() && std::equal(drive.begin(), drive.end(), offered_.begin())) {
    base = unlimited_;
  } else {
    base.assign(drive.begin(), drive.end());
    if (updates_ == 0) low_pass(base);
  }
  ++updates_;
  const double span = o_.u_max - o_.u_min;
  const double reach = std::isfinite(span) ? kBeyondLimits * span : 0.0;
  unlimited_.resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    unlimited_[j] = std::clamp(base[j] + c[j], o_.u_min - reach, o_.u_max + reach);
    next[j] = std::clamp(unlimited_[j], o_.u_min, o_.u_max);
  }
  // The slew limit, around the trial: each sample within max_step of the one before.
  for (int round = 0; round < 2; ++round) {
    for (std::size_t j = 0; j < n; ++j) {
      const double before = next[(j + n - 1) % n];
      next[j] = std::clamp(next[j], before - o_.max_step, before + o_.max_step);
    }
  }
  offered_.assign(next.begin(), next.end());
}

}  // namespace hystbench::compensation
