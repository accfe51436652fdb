#include "hystbench/compensation/amplitude_scheduled_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hystbench::compensation {

Eigen::VectorXd schedule_weights(std::span<const double> amplitudes, double a) {
  const std::size_t n = amplitudes.size();
  if (n == 0) throw std::invalid_argument("schedule: no amplitude");
  Eigen::VectorXd w = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
  if (n == 1) {
    w(0) = 1.0;
    return w;
  }
  // The pair of neighbouring amplitudes that holds a, or the end pair nearest to it.
  std::size_t lo = 0;
  while (lo + 2 < n && a > amplitudes[lo + 1]) ++lo;
  const double a0 = amplitudes[lo], a1 = amplitudes[lo + 1];
  const double lowest = lo == 0 ? -1.0 : 0.0, highest = lo + 2 == n ? 2.0 : 1.0;
  const double s = std::clamp((a - a0) / (a1 - a0), lowest, highest);
  w(static_cast<Eigen::Index>(lo)) = 1.0 - s;
  w(static_cast<Eigen::Index>(lo + 1)) = s;
  return w;
}

Eigen::VectorXd amplitude_estimate(const Eigen::MatrixXd& u, std::size_t window) {
  if (window == 0) throw std::invalid_argument("amplitude estimate: a window of 1 sample or more");
  const Eigen::Index m = u.rows(), n = u.cols();
  Eigen::VectorXd a(n);
  if (m == 0) return Eigen::VectorXd::Zero(n);
  // Running sums over the window, per input; each sample's value relative to the input's first,
  // so that a large constant bias does not cost precision in the difference of the sums.
  Eigen::VectorXd s1 = Eigen::VectorXd::Zero(m), s2 = Eigen::VectorXd::Zero(m);
  const Eigen::VectorXd base = n > 0 ? Eigen::VectorXd(u.col(0)) : Eigen::VectorXd::Zero(m);
  const auto w = static_cast<Eigen::Index>(window);
  for (Eigen::Index t = 0; t < n; ++t) {
    const Eigen::VectorXd x = u.col(t) - base;
    s1 += x;
    s2 += x.cwiseProduct(x);
    if (t >= w) {
      const Eigen::VectorXd old = u.col(t - w) - base;
      s1 -= old;
      s2 -= old.cwiseProduct(old);
    }
    const double count = static_cast<double>(std::min(t + 1, w));
    double var = 0.0;
    for (Eigen::Index j = 0; j < m; ++j) {
      const double mean = s1(j) / count;
      var += std::max(s2(j) / count - mean * mean, 0.0);
    }
    a(t) = std::sqrt(var / static_cast<double>(m));
  }
  return a;
}

double record_amplitude(const Eigen::MatrixXd& u) {
  if (u.rows() == 0 || u.cols() == 0) return 0.0;
  double var = 0.0;
  for (Eigen::Index j = 0; j < u.rows(); ++j) {
    const double mean = u.row(j).mean();
    var += (u.row(j).array() - mean).square().mean();
  }
  return std::sqrt(var / static_cast<double>(u.rows()));
}

AmplitudeScheduledMimoModel::AmplitudeScheduledMimoModel(std::vector<double> amplitudes,
                                                         std::vector<HammersteinMimoModel> local,
                                                         double window_s)
    : amplitudes_(std::move(amplitudes)), local_(std::move(local)), window_s_(window_s) {
  const std::string what = "amplitude-scheduled model: ";
  if (local_.empty() || local_.size() != amplitudes_.size()) {
    throw std::invalid_argument(what + "one amplitude per local model, one or more");
  }
  for (std::size_t i = 0; i < amplitudes_.size(); ++i) {
    if (!(std::isfinite(amplitudes_[i]) && amplitudes_[i] > 0.0) ||
        (i > 0 && !(amplitudes_[i] > amplitudes_[i - 1]))) {
      throw std::invalid_argument(what + "amplitudes > 0, ascending and distinct");
    }
    const HammersteinMimoModel& l = local_[i];
    if (l.inputs() != inputs() || l.outputs() != outputs() ||
        std::abs(l.sample_period_s() - sample_period_s()) > 1e-9 * sample_period_s()) {
      throw std::invalid_argument(what + "local model " + std::to_string(i) +
                                  " differs in inputs, outputs or sample period");
    }
  }
  if (!(std::isfinite(window_s_) && window_s_ > 0.0)) {
    throw std::invalid_argument(what + "a window > 0 s");
  }
}

std::size_t AmplitudeScheduledMimoModel::window_samples() const noexcept {
  return static_cast<std::size_t>(std::max(1.0, std::round(window_s_ / sample_period_s())));
}

Eigen::MatrixXd AmplitudeScheduledMimoModel::simulate(const Eigen::MatrixXd& u) const {
  if (local_.size() == 1) return local_.front().simulate(u);
  std::vector<Eigen::MatrixXd> y;
  y.reserve(local_.size());
  for (const auto& l : local_) y.push_back(l.simulate(u));
  const Eigen::VectorXd a = amplitude_estimate(u, window_samples());
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(outputs()), u.cols());
  for (Eigen::Index t = 0; t < u.cols(); ++t) {
    const Eigen::VectorXd w = schedule_weights(amplitudes_, a(t));
    for (std::size_t i = 0; i < local_.size(); ++i) {
      const double wi = w(static_cast<Eigen::Index>(i));
      if (wi != 0.0) out.col(t) += wi * y[i].col(t);
    }
  }
  return out;
}

AmplitudeScheduledMimoModel AmplitudeScheduledMimoModel::without(std::size_t i) const {
  if (local_.size() < 2 || i >= local_.size()) {
    throw std::invalid_argument("amplitude-scheduled model: nothing left without local model " +
                                std::to_string(i));
  }
  std::vector<double> a = amplitudes_;
  std::vector<HammersteinMimoModel> l = local_;
  a.erase(a.begin() + static_cast<std::ptrdiff_t>(i));
  l.erase(l.begin() + static_cast<std::ptrdiff_t>(i));
  return {std::move(a), std::move(l), window_s_};
}

}  // namespace hystbench::compensation
