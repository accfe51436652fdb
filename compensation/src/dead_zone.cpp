#include "hystbench/compensation/dead_zone.hpp"

#include <algorithm>
#include <string>

#include "details/validate.hpp"

namespace hystbench::compensation {

std::vector<double> uniform_dead_zone_thresholds(std::size_t m, double below, double above) {
  std::vector<double> d(2 * m + 1, 0.0);
  for (std::size_t j = 1; j <= m; ++j) {
    const double f = static_cast<double>(j) / static_cast<double>(m + 1);
    d[m + j] = f * above;
    d[m - j] = -f * below;
  }
  return d;
}

DeadZoneSuperposition::DeadZoneSuperposition() : p_{{0.0}, {1.0}}, zero_(0), w0_(1.0) {}

DeadZoneSuperposition::DeadZoneSuperposition(DeadZoneParameters p) : p_(std::move(p)) {
  details::require(!p_.thresholds.empty(), "deadzone.thresholds must not be empty");
  details::require_same_size(p_.thresholds.size(), p_.weights.size(), "deadzone.thresholds",
                             "deadzone.weights");
  details::require_finite(p_.thresholds, "deadzone.thresholds");
  details::require_finite(p_.weights, "deadzone.weights");
  details::require_strictly_increasing(p_.thresholds, "deadzone.thresholds");
  const auto it = std::find(p_.thresholds.begin(), p_.thresholds.end(), 0.0);
  details::require(it != p_.thresholds.end(),
                   "deadzone.thresholds must contain 0 (the identity operator)");
  zero_ = static_cast<std::size_t>(it - p_.thresholds.begin());
  w0_ = p_.weights[zero_];
  for (std::size_t j = zero_ + 1; j < p_.thresholds.size(); ++j) {
    pos_d_.push_back(p_.thresholds[j]);
    pos_w_.push_back(p_.weights[j]);
  }
  for (std::size_t j = 0; j < zero_; ++j) {
    neg_d_.push_back(p_.thresholds[j]);
    neg_w_.push_back(p_.weights[j]);
  }
}

double DeadZoneSuperposition::slope(double v) const noexcept {
  double s = w0_;
  for (std::size_t j = 0; j < pos_d_.size(); ++j) s += v > pos_d_[j] ? pos_w_[j] : 0.0;
  for (std::size_t j = 0; j < neg_d_.size(); ++j) s += v < neg_d_[j] ? neg_w_[j] : 0.0;
  return s;
}

double DeadZoneSuperposition::apply(double v) const noexcept {
  double zp = 0.0, zn = 0.0;
  for (std::size_t j = 0; j < pos_d_.size(); ++j) {
    const double e = v - pos_d_[j];
    zp += pos_w_[j] * (e > 0.0 ? e : 0.0);
  }
  for (std::size_t j = 0; j < neg_d_.size(); ++j) {
    const double e = v - neg_d_[j];
    zn += neg_w_[j] * (e < 0.0 ? e : 0.0);
  }
  return w0_ * v + zp + zn;
}

Invertibility DeadZoneSuperposition::invertibility() const {
  auto fail = [](std::size_t index, double value, const std::string& side) {
    Invertibility v;
    v.invertible = false;
    v.block = "deadzone";
    v.index = static_cast<int>(index);
    v.value = value;
    v.reason = "cumulative dead-zone weight at deadzone index " + std::to_string(index) + " (" +
               side + " side) = " + std::to_string(value) + " is not positive";
    return v;
  };
  double w = 0.0;
  for (std::size_t j = zero_; j < p_.weights.size(); ++j) {
    w += p_.weights[j];
    if (!(w > 0.0)) return fail(j, w, "positive");
  }
  w = p_.weights[zero_];
  for (std::size_t j = zero_; j-- > 0;) {
    w += p_.weights[j];
    if (!(w > 0.0)) return fail(j, w, "negative");
  }
  return Invertibility::ok();
}

DeadZoneSuperposition DeadZoneSuperposition::inverse() const {
  const Invertibility inv = invertibility();
  if (!inv.invertible) throw NotInvertibleError(inv);
  const auto& d = p_.thresholds;
  const auto& w = p_.weights;
  const std::size_t n = d.size();
  DeadZoneParameters out{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
  out.weights[zero_] = 1.0 / w[zero_];
  // Positive side: d'_i = sum_{j=0..i} w_j (d_i - d_j), w'_i = -w_i / (W_i W_{i-1}).
  double cum_prev = w[zero_];
  for (std::size_t i = zero_ + 1; i < n; ++i) {
    double di = 0.0;
    for (std::size_t j = zero_; j <= i; ++j) di += w[j] * (d[i] - d[j]);
    out.thresholds[i] = di;
    const double cum = cum_prev + w[i];
    out.weights[i] = -w[i] / (cum * cum_prev);
    cum_prev = cum;
  }
  // Negative side, mirrored outward from zero.
  cum_prev = w[zero_];
  for (std::size_t i = zero_; i-- > 0;) {
    double di = 0.0;
    for (std::size_t j = i; j <= zero_; ++j) di += w[j] * (d[i] - d[j]);
    out.thresholds[i] = di;
    const double cum = cum_prev + w[i];
    out.weights[i] = -w[i] / (cum * cum_prev);
    cum_prev = cum;
  }
  return DeadZoneSuperposition(std::move(out));
}

}  // namespace hystbench::compensation
