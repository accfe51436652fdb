#include "hystbench/compensation/stage_dynamic_decoupling.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

#include "hystbench/compensation/measured_modes.hpp"
#include "hystbench/compensation/stage_decoupling.hpp"

namespace hystbench::compensation {

namespace {

[[noreturn]] void refuse(const std::string& what) { throw std::invalid_argument(what); }

constexpr int kMaxSweeps = 50;
constexpr double kTolerance = 1e-9;  // of the reference's largest magnitude
constexpr double kGiveUp = 1e-6;     // what is left after kMaxSweeps that counts as converged
// A path's lag, in twentieths of a sample: from a lead of 2 samples (a path over a receiving
// axis that lags more than the path) to a lag of 3.
constexpr int kLeadSteps = -40;
constexpr int kLagSteps = 60;

// The mean of a response over its lowest tenth of lines (at least one).
std::complex<double> low_frequency_mean(const MeasuredResponse& r) {
  const std::size_t low = std::clamp<std::size_t>(r.size() / 10, 1, r.size());
  std::complex<double> sum = 0.0;
  for (std::size_t i = 0; i < low; ++i) sum += r.response[i];
  return sum / static_cast<double>(low);
}

// SecondOrderDynamics' response at f: y(k) = [1 0] x(k + 1), x(k + 1) = Phi x(k) + Gam u(k),
// so Y / U = [1 0] z (z I - Phi)^-1 Gam with z = exp(j 2 pi f dt).
std::complex<double> held_mode_response(const DynamicsParameters& p, double f, double dt_s) {
  const SecondOrderDynamics d(p, dt_s);
  const std::complex<double> z = std::polar(1.0, 2.0 * std::numbers::pi * f * dt_s);
  const std::complex<double> a = z - d.phi(0, 0), b = -d.phi(0, 1), c = -d.phi(1, 0),
                             e = z - d.phi(1, 1);
  const std::complex<double> det = a * e - b * c;
  // First row of (z I - Phi)^-1 is [e, -b] / det.
  return z * (e * d.gam(0) - b * d.gam(1)) / det;
}

// Every path's filter over one axis's stroke, into `out` (same length): direct x + sum of each
// mode's share of its response, each mode settled at the stroke's first value.
void filter_path(const CouplingPathShape& shape, double dt_s, const Eigen::RowVectorXd& stroke,
                 Eigen::RowVectorXd& out) {
  // The lag first (linear between samples, a lead reading ahead; past either end, the end),
  // then the direct share and each mode's.
  const Eigen::Index n = stroke.size();
  Eigen::RowVectorXd lagged(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double at =
        std::clamp(static_cast<double>(k) - shape.lag_samples, 0.0, static_cast<double>(n - 1));
    const auto i = static_cast<Eigen::Index>(std::floor(at));
    const double f = at - static_cast<double>(i);
    lagged(k) = i + 1 < n ? (1.0 - f) * stroke(i) + f * stroke(i + 1) : stroke(i);
  }
  out = shape.direct * lagged;
  // The central differences (their ends the one-sided ones a held end gives).
  for (Eigen::Index k = 0; k < n; ++k) {
    const double before = lagged(std::max<Eigen::Index>(k - 1, 0));
    const double after = lagged(std::min<Eigen::Index>(k + 1, n - 1));
    out(k) +=
        shape.slope * 0.5 * (after - before) + shape.curvature * (after - 2.0 * lagged(k) + before);
  }
  for (const CouplingPathShape::Mode& m : shape.modes) {
    SecondOrderDynamics mode(m.parameters, dt_s);
    mode.reset(lagged(0));
    // Sample k's coupling: the mode's output at the end of the sample over which the stroke is
    // held, where a model places its own displacement too.
    for (Eigen::Index k = 0; k < n; ++k) out(k) += m.share * mode.step(lagged(k));
  }
}

// Operating point k's path over the receiving axis's response as its feedforward leaves it,
// each at unit low-frequency gain, on the lines both have with coherence >= 0.5; empty where
// none is usable.
MeasuredResponse path_over_own(const MeasuredResponse& c, const MeasuredResponse* o,
                               const std::optional<DynamicsParameters>& inverted, double dt_s) {
  MeasuredResponse path;
  path.label = c.label;
  const std::complex<double> c_dc = low_frequency_mean(c);
  const std::complex<double> o_dc = o != nullptr ? low_frequency_mean(*o) : 1.0;
  if (!(std::abs(c_dc) > 0.0) || !(std::abs(o_dc) > 0.0)) return path;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (i < c.coherence.size() && c.coherence[i] < 0.5) continue;
    const double f = c.frequency_hz[i];
    std::complex<double> v = c.response[i] / c_dc;
    if (o != nullptr) {
      const auto it =
          std::lower_bound(o->frequency_hz.begin(), o->frequency_hz.end(), f * (1.0 - 1e-9));
      if (it == o->frequency_hz.end() || std::abs(*it - f) > 1e-9 * f) continue;
      const auto at = static_cast<std::size_t>(it - o->frequency_hz.begin());
      if (at < o->coherence.size() && o->coherence[at] < 0.5) continue;
      std::complex<double> seen = o->response[at] / o_dc;
      if (inverted) seen /= held_mode_response(*inverted, f, dt_s);
      if (!(std::abs(seen) > 0.0)) continue;
      v /= seen;
    }
    path.frequency_hz.push_back(f);
    path.response.push_back(v);
    path.noise.push_back(0.0);
    path.coherence.push_back(1.0);
  }
  return path;
}

// The least-squares columns at each line: for each mode its response less 1, then the central
// first and second differences' responses; real and imaginary parts in turn.
Eigen::MatrixXd shape_columns(std::span<const double> lines,
                              std::span<const DynamicsParameters> modes, double dt_s) {
  const auto rows = static_cast<Eigen::Index>(lines.size());
  const auto mode_cols = static_cast<Eigen::Index>(modes.size());
  Eigen::MatrixXd a(2 * rows, mode_cols + 2);
  for (Eigen::Index k = 0; k < rows; ++k) {
    const double f = lines[static_cast<std::size_t>(k)];
    for (Eigen::Index m = 0; m < mode_cols; ++m) {
      const std::complex<double> c =
          held_mode_response(modes[static_cast<std::size_t>(m)], f, dt_s) - 1.0;
      a(2 * k, m) = c.real();
      a(2 * k + 1, m) = c.imag();
    }
    const double wt = 2.0 * std::numbers::pi * f * dt_s;
    a(2 * k, mode_cols) = 0.0;  // (x(k+1) - x(k-1)) / 2: j sin(w dt)
    a(2 * k + 1, mode_cols) = std::sin(wt);
    a(2 * k, mode_cols + 1) = 2.0 * std::cos(wt) - 2.0;  // x(k+1) - 2 x(k) + x(k-1)
    a(2 * k + 1, mode_cols + 1) = 0.0;
  }
  return a;
}

}  // namespace

std::optional<CouplingPathShape> coupling_path(std::span<const MeasuredResponse> cross,
                                               std::span<const MeasuredResponse> own,
                                               const std::optional<DynamicsParameters>& inverted,
                                               double dt_s) {
  if (cross.empty() || !(dt_s > 0.0)) return std::nullopt;
  std::vector<MeasuredResponse> paths;
  for (std::size_t k = 0; k < cross.size(); ++k) {
    const MeasuredResponse* o = own.empty() ? nullptr : (k < own.size() ? &own[k] : nullptr);
    if (cross[k].size() == 0 || (!own.empty() && (o == nullptr || o->size() == 0))) continue;
    MeasuredResponse path = path_over_own(cross[k], o, inverted, dt_s);
    if (path.size() > 0) paths.push_back(std::move(path));
  }
  std::vector<DynamicsParameters> modes;
  for (const MeasuredMode& m : measured_modes(paths)) {
    if (m.frequency_hz > 0.0 && m.damping_ratio > 0.0 && m.frequency_hz < 0.5 / dt_s) {
      modes.push_back({m.frequency_hz, m.damping_ratio});
    }
  }
  if (modes.empty()) return std::nullopt;
  std::vector<double> lines;
  std::vector<std::complex<double>> shape;
  for (const MeasuredResponse& path : paths) {
    lines.insert(lines.end(), path.frequency_hz.begin(), path.frequency_hz.end());
    shape.insert(shape.end(), path.response.begin(), path.response.end());
  }
  const auto rows = static_cast<Eigen::Index>(lines.size());
  const auto mode_cols = static_cast<Eigen::Index>(modes.size());
  if (rows < 2 * (mode_cols + 2) + 2) return std::nullopt;
  // P e^{j w tau} - 1 = sum_m w_m (M_m - 1) + a D1 + b D2: linear in the shares and weights
  // for each lag tau.
  const Eigen::MatrixXd a = shape_columns(lines, modes, dt_s);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  std::optional<CouplingPathShape> best;
  Eigen::VectorXd b(2 * rows);
  for (int step = kLeadSteps; step <= kLagSteps; ++step) {
    const double lag = static_cast<double>(step) / 20.0;
    for (Eigen::Index k = 0; k < rows; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      const std::complex<double> v =
          shape[ku] * std::polar(1.0, 2.0 * std::numbers::pi * lines[ku] * lag * dt_s) - 1.0;
      b(2 * k) = v.real();
      b(2 * k + 1) = v.imag();
    }
    const Eigen::VectorXd w = qr.solve(b);
    if (!w.allFinite()) continue;
    const double misfit = std::sqrt((a * w - b).squaredNorm() / static_cast<double>(rows));
    if (best && misfit >= best->misfit) continue;
    CouplingPathShape fitted;
    fitted.lag_samples = lag;
    fitted.misfit = misfit;
    for (Eigen::Index m = 0; m < mode_cols; ++m) {
      fitted.modes.push_back({modes[static_cast<std::size_t>(m)], w(m)});
      fitted.direct -= w(m);
    }
    fitted.slope = w(mode_cols);
    fitted.curvature = w(mode_cols + 1);
    best = std::move(fitted);
  }
  return best;
}

DynamicStageDecoupler::DynamicStageDecoupler(const Eigen::MatrixXd& gains, PathShapes paths,
                                             double dt_s)
    : gains_(gains), paths_(std::move(paths)), dt_s_(dt_s) {
  // The static decoupler's rules on the gains (and its inverse, the substitutions' start).
  static_cast<void>(StageDecoupler(gains));
  static_inverse_ = (Eigen::MatrixXd::Identity(gains.rows(), gains.cols()) + gains).inverse();
  if (!(std::isfinite(dt_s) && dt_s > 0.0)) refuse("dynamic decoupler: dt must be > 0");
  const std::size_t n = axes();
  if (paths_.empty()) return;
  if (paths_.size() != n) {
    refuse("dynamic decoupler: paths for " + std::to_string(paths_.size()) + " axes, gains for " +
           std::to_string(n));
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (paths_[i].size() != n) {
      refuse("dynamic decoupler: paths row " + std::to_string(i) + " has " +
             std::to_string(paths_[i].size()) + " paths, not " + std::to_string(n));
    }
    paths_[i][i].reset();  // an axis's own dynamics are its model's
    for (std::size_t j = 0; j < n; ++j) {
      if (!paths_[i][j]) continue;
      const std::string which =
          "dynamic decoupler: path " + std::to_string(i) + " <- " + std::to_string(j) + ": ";
      if (!std::isfinite(paths_[i][j]->direct) || !std::isfinite(paths_[i][j]->slope) ||
          !std::isfinite(paths_[i][j]->curvature)) {
        refuse(which + "a share or weight is not finite");
      }
      if (!(std::abs(paths_[i][j]->lag_samples) <= 1e6)) {
        refuse(which + "its lag must be in [-1e6, 1e6] samples");
      }
      for (const CouplingPathShape::Mode& m : paths_[i][j]->modes) {
        if (!std::isfinite(m.share)) refuse(which + "a mode's share is not finite");
        try {
          SecondOrderDynamics check(m.parameters, dt_s);
        } catch (const std::exception& e) {
          refuse(which + e.what());
        }
      }
    }
  }
}

bool DynamicStageDecoupler::dynamic() const noexcept {
  for (const auto& row : paths_) {
    for (const auto& p : row) {
      if (p && !p->modes.empty()) return true;
    }
  }
  return false;
}

DynamicStageDecoupler::Solution DynamicStageDecoupler::own_targets(
    const Eigen::MatrixXd& stage, std::span<const StrokeOf> strokes) const {
  const auto n = static_cast<Eigen::Index>(axes());
  if (stage.rows() != n) {
    refuse("dynamic decoupler: a reference of " + std::to_string(stage.rows()) + " axes for " +
           std::to_string(n));
  }
  if (!strokes.empty() && strokes.size() != axes()) {
    refuse("dynamic decoupler: " + std::to_string(strokes.size()) + " strokes for " +
           std::to_string(n) + " axes");
  }
  if (!stage.allFinite()) refuse("dynamic decoupler: a reference value is not a finite number");
  const Eigen::Index samples = stage.cols();
  Solution out;
  out.own = static_inverse_ * stage;
  if (samples == 0 || !dynamic()) return out;
  const double scale = std::max(stage.cwiseAbs().maxCoeff(), 1e-12);

  Eigen::MatrixXd stroke(n, samples), next(n, samples);
  Eigen::RowVectorXd filtered(samples);
  std::vector<double> own_row(static_cast<std::size_t>(samples));
  std::vector<double> stroke_row(static_cast<std::size_t>(samples));
  double previous = 0.0;
  for (int sweep = 1; sweep <= kMaxSweeps; ++sweep) {
    for (Eigen::Index j = 0; j < n; ++j) {
      const auto ju = static_cast<std::size_t>(j);
      if (strokes.empty() || !strokes[ju]) {
        stroke.row(j) = out.own.row(j);
        continue;
      }
      for (Eigen::Index k = 0; k < samples; ++k)
        own_row[static_cast<std::size_t>(k)] = out.own(j, k);
      strokes[ju](own_row, stroke_row);
      for (Eigen::Index k = 0; k < samples; ++k)
        stroke(j, k) = stroke_row[static_cast<std::size_t>(k)];
    }
    next = stage;
    for (Eigen::Index i = 0; i < n; ++i) {
      for (Eigen::Index j = 0; j < n; ++j) {
        const double k_ij = gains_(i, j);
        if (i == j || k_ij == 0.0) continue;
        const std::optional<CouplingPathShape>* path =
            paths_.empty() ? nullptr
                           : &paths_[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
        if (path == nullptr || !path->has_value()) {
          next.row(i) -= k_ij * stroke.row(j);
          continue;
        }
        filter_path(**path, dt_s_, stroke.row(j), filtered);
        next.row(i) -= k_ij * filtered;
      }
    }
    if (!next.allFinite()) refuse("dynamic decoupler: the substitutions diverged (not finite)");
    out.change = (next - out.own).cwiseAbs().maxCoeff();
    out.own.swap(next);
    out.sweeps = sweep;
    if (out.change <= kTolerance * scale) return out;
    if (sweep > 5 && out.change > previous) {
      refuse(
          "dynamic decoupler: the substitutions diverge (the coupling at its mode is too strong "
          "to be taken out this way)");
    }
    previous = out.change;
  }
  if (out.change > kGiveUp * scale) {
    refuse("dynamic decoupler: no convergence in " + std::to_string(kMaxSweeps) +
           " substitutions (change " + std::to_string(out.change) + ")");
  }
  return out;
}

}  // namespace hystbench::compensation
