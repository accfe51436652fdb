#include "hystbench/compensation/step_timing.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <unsupported/Eigen/LevenbergMarquardt>
#include <vector>

#include "details/diagnosis_signals.hpp"
#include "details/forward_difference.hpp"
#include "hystbench/compensation/delay_line.hpp"
#include "hystbench/compensation/second_order_dynamics.hpp"

namespace hystbench::compensation {

namespace {

constexpr std::size_t kBefore = 5;         // samples of the hold before the step
constexpr std::size_t kMinAfter = 20;      // samples of the hold after it, at least
constexpr double kWindowSeconds = 0.03;    // window after the step, at most
constexpr double kWindowPeriods = 12.0;    // ... or this many periods of the lowest frequency
constexpr double kFrequencySpan = 4.0;     // factor below the start
constexpr double kDelaySpan = 2.5;         // samples either side of the start
constexpr double kDelayGridStep = 0.25;    // samples
constexpr int kFrequenciesPerDecade = 40;  // grid
constexpr double kZetaGrid[] = {0.02, 0.05, 0.1, 0.2, 0.4, 0.8};
constexpr double kZetaMin = 0.003, kZetaMax = 1.0;
constexpr int kMaxEvaluations = 200;

struct Window {
  std::size_t begin = 0, end = 0;  ///< from 5 samples before the step to the window's end
};

// The record's steps with the input held around them, each window up to `window` samples after.
std::vector<Window> step_windows(std::span<const double> u, std::size_t window) {
  std::vector<Window> windows;
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  const double tolerance = 1e-6 * std::max(1e-12, *hi - *lo);
  for (const std::size_t k : details::find_steps(u)) {
    if (k < kBefore) continue;
    Window w{k - kBefore, k};
    bool held = true;
    for (std::size_t j = w.begin; j < k && held; ++j)
      held = std::abs(u[j] - u[w.begin]) <= tolerance;
    while (w.end < u.size() && w.end < k + window && std::abs(u[w.end] - u[k]) <= tolerance)
      ++w.end;
    if (held && w.end - k >= kMinAfter) windows.push_back(w);
  }
  return windows;
}

// The residuals of y ~ a + b x + c t over every window (a, b, c fitted per window: variable
// projection), x the input through the delay and the dynamics.
class TimingObjective {
 public:
  TimingObjective(std::span<const double> u, std::span<const double> y, double dt,
                  std::vector<Window> windows)
      : u_(u), y_(y), dt_(dt), windows_(std::move(windows)) {
    for (const Window& w : windows_) rows_ += w.end - w.begin;
    x_.resize(rows_);
    e_.resize(static_cast<Eigen::Index>(rows_));
  }
  bool empty() const noexcept { return windows_.empty(); }
  std::size_t size() const noexcept { return windows_.size(); }
  std::size_t rows() const noexcept { return rows_; }

  /// Writes rows() residuals to `out`.
  void residuals(double fn, double zeta, double delay, double* out) const {
    std::size_t row = 0;
    for (const Window& w : windows_) {
      DelayLine line = DelayLine::of(delay);
      SecondOrderDynamics d({fn, zeta}, dt_);
      line.reset(u_[w.begin]);
      d.reset(u_[w.begin]);
      Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
      Eigen::Vector3d aty = Eigen::Vector3d::Zero();
      for (std::size_t k = w.begin; k < w.end; ++k) {
        x_[row + k - w.begin] = d.step(line.push(u_[k]));
        const Eigen::Vector3d a(1.0, x_[row + k - w.begin], static_cast<double>(k - w.begin));
        ata.noalias() += a * a.transpose();
        aty += a * y_[k];
      }
      const Eigen::Vector3d c = ata.ldlt().solve(aty);
      for (std::size_t k = w.begin; k < w.end; ++k, ++row) {
        out[row] = y_[k] - (c[0] + c[1] * x_[row] + c[2] * static_cast<double>(k - w.begin));
      }
    }
  }
  /// Mean square of the residuals.
  double operator()(double fn, double zeta, double delay) const {
    if (rows_ == 0) return std::numeric_limits<double>::infinity();
    residuals(fn, zeta, delay, e_.data());
    return e_.squaredNorm() / static_cast<double>(rows_);
  }

 private:
  std::span<const double> u_, y_;
  double dt_;
  std::vector<Window> windows_;
  std::size_t rows_ = 0;
  mutable std::vector<double> x_;  // the input through the delay and dynamics, per row
  mutable Eigen::VectorXd e_;      // the residuals, per row
};

// The residuals in (delay [samples], log natural frequency, log damping) for Eigen's
// Levenberg-Marquardt, with forward-difference derivatives.
struct TimingResiduals : Eigen::DenseFunctor<double> {
  explicit TimingResiduals(const TimingObjective& j)
      : Eigen::DenseFunctor<double>(3, static_cast<int>(j.rows())), j_(j) {}
  int operator()(const InputType& p, ValueType& f) const {
    j_.residuals(std::exp(p[1]), std::exp(p[2]), p[0], f.data());
    return 0;
  }
  int df(const InputType& p, JacobianType& jac) const {
    details::forward_difference_jacobian(*this, p, jac, 1e-4);
    return 0;
  }
  const TimingObjective& j_;
};

}  // namespace

std::optional<StepTiming> fit_step_timing(std::span<const double> u, std::span<const double> y,
                                          double dt_s, const StepTiming& start) {
  if (u.size() != y.size() || !(dt_s > 0.0) || !(start.natural_frequency_hz > 0.0) ||
      !(start.damping_ratio > 0.0)) {
    return std::nullopt;
  }
  // Up to 0.45 of the sample rate whatever the start: a record-wide fit can put the mode far
  // below the one the steps show (the loop's shape it misses pulls it down).
  const double f_lo = start.natural_frequency_hz / kFrequencySpan;
  const double f_hi = 0.45 / dt_s;
  if (f_lo >= f_hi) return std::nullopt;
  const double window_s = std::max(kWindowSeconds, kWindowPeriods / f_lo);
  const TimingObjective j(u, y, dt_s,
                          step_windows(u, static_cast<std::size_t>(std::lround(window_s / dt_s))));
  if (j.empty()) return std::nullopt;
  const double d_lo = std::max(0.0, start.delay_samples - kDelaySpan);
  const double d_hi = start.delay_samples + kDelaySpan;
  // A grid over the delay, the frequency and a few dampings (the objective has narrow valleys
  // along which delay and frequency trade, where a search one parameter at a time stalls)...
  std::array<double, 3> best{start.delay_samples, std::log(start.natural_frequency_hz),
                             std::log(start.damping_ratio)};
  const auto at = [&j](const std::array<double, 3>& p) {
    return j(std::exp(p[1]), std::exp(p[2]), p[0]);
  };
  double least = at(best);
  const double f_step = std::log(10.0) / kFrequenciesPerDecade;
  for (const double zeta : kZetaGrid) {
    for (double lf = std::log(f_lo); lf <= std::log(f_hi); lf += f_step) {
      for (double d = d_lo; d <= d_hi + 1e-9; d += kDelayGridStep) {
        const std::array<double, 3> p{d, lf, std::log(zeta)};
        const double v = at(p);
        if (v < least) least = v, best = p;
      }
    }
  }
  // ... then Levenberg-Marquardt from the best grid point, kept when it is better within the
  // brackets.
  TimingResiduals functor(j);
  Eigen::LevenbergMarquardt<TimingResiduals> lm(functor);
  lm.setMaxfev(kMaxEvaluations);
  Eigen::VectorXd p(3);
  p << best[0], best[1], best[2];
  lm.minimize(p);
  const bool inside = p[0] >= d_lo && p[0] <= d_hi && p[1] >= std::log(f_lo) &&
                      p[1] <= std::log(f_hi) && p[2] >= std::log(kZetaMin) &&
                      p[2] <= std::log(kZetaMax);
  if (inside && at({p[0], p[1], p[2]}) < least) best = {p[0], p[1], p[2]};
  StepTiming t;
  t.delay_samples = best[0];
  t.natural_frequency_hz = std::exp(best[1]);
  t.damping_ratio = std::exp(best[2]);
  t.rms = std::sqrt(j(t.natural_frequency_hz, t.damping_ratio, t.delay_samples));
  t.steps = j.size();
  return t;
}

}  // namespace hystbench::compensation
