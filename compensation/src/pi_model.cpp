#include "hystbench/compensation/pi_model.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "details/play_kernels.hpp"
#include "details/validate.hpp"

namespace hystbench::compensation {

namespace {

void validate(const PiParameters& p) {
  details::require(!p.thresholds.empty(), "play.thresholds must not be empty");
  details::require_same_size(p.thresholds.size(), p.weights.size(), "play.thresholds",
                             "play.weights");
  details::require_finite(p.thresholds, "play.thresholds");
  details::require_finite(p.weights, "play.weights");
  details::require_finite(p.offset, "play.offset");
  details::require(p.thresholds.front() >= 0.0, "play.thresholds[0] must be >= 0");
  details::require_strictly_increasing(p.thresholds, "play.thresholds");
}

}  // namespace

std::vector<double> uniform_thresholds(std::size_t n, double r_max) {
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i)
    r[i] = r_max * static_cast<double>(i) / static_cast<double>(n);
  return r;
}

PiModel::PiModel(PiParameters p) : p_(std::move(p)), state_(p_.thresholds.size(), 0.0) {
  validate(p_);
}

double PiModel::step(double u) noexcept {
  return details::play_step(u, p_.thresholds.data(), p_.weights.data(), state_.data(),
                            state_.size()) +
         p_.offset;
}

double PiModel::peek(double u) const noexcept {
  const double* r = p_.thresholds.data();
  const double* w = p_.weights.data();
  const double* s = state_.data();
  const std::size_t n = state_.size();
  double a0 = 0.0, a1 = 0.0;
  std::size_t i = 0;
  for (; i + 2 <= n; i += 2) {
    a0 += w[i] * std::max(u - r[i], std::min(u + r[i], s[i]));
    a1 += w[i + 1] * std::max(u - r[i + 1], std::min(u + r[i + 1], s[i + 1]));
  }
  for (; i < n; ++i) a0 += w[i] * std::max(u - r[i], std::min(u + r[i], s[i]));
  return a0 + a1 + p_.offset;
}

void PiModel::reset(double u0) noexcept { std::fill(state_.begin(), state_.end(), u0); }

Invertibility PiModel::invertibility() const {
  if (p_.thresholds.front() != 0.0) {
    Invertibility v;
    v.invertible = false;
    v.block = "play";
    v.index = 0;
    v.value = p_.thresholds.front();
    v.reason = "play.thresholds[0] must be 0 (a first threshold of " + std::to_string(v.value) +
               " leaves a flat backlash after every reversal)";
    return v;
  }
  return check_cumulative_weights(p_.weights.data(), p_.weights.size(), "play",
                                  "cumulative play weight");
}

std::unique_ptr<HysteresisModel> PiModel::clone() const { return std::make_unique<PiModel>(*this); }

void PiModel::set_state(std::span<const double> play_outputs) {
  details::require_same_size(play_outputs.size(), state_.size(), "state", "play.thresholds");
  std::copy(play_outputs.begin(), play_outputs.end(), state_.begin());
}

double PiModel::weighted_sum(std::span<const double> play_outputs) const noexcept {
  double y = 0.0;
  const std::size_t n = std::min(play_outputs.size(), p_.weights.size());
  for (std::size_t i = 0; i < n; ++i) y += p_.weights[i] * play_outputs[i];
  return y;
}

PiParameters inverse_parameters(const PiParameters& model) {
  const PiModel m(model);  // validates
  const Invertibility inv = m.invertibility();
  if (!inv.invertible) throw NotInvertibleError(inv);
  const std::size_t n = model.weights.size();
  PiParameters out;
  out.thresholds.resize(n);
  out.weights.resize(n);
  out.offset = 0.0;
  double cum_prev = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    double r = 0.0;
    for (std::size_t j = 0; j <= i; ++j)
      r += model.weights[j] * (model.thresholds[i] - model.thresholds[j]);
    out.thresholds[i] = r;
    const double cum = cum_prev + model.weights[i];
    out.weights[i] = (i == 0) ? 1.0 / cum : -model.weights[i] / (cum * cum_prev);
    cum_prev = cum;
  }
  return out;
}

std::vector<double> inverse_state(const PiParameters& model, std::span<const double> play_outputs) {
  const std::size_t n = model.weights.size();
  details::require_same_size(play_outputs.size(), n, "state", "play.weights");
  // p'_i = W_i p_i + sum_{j>i} w_j p_j, computed with a suffix sum in O(n).
  std::vector<double> out(n);
  std::vector<double> cumulative(n);
  double c = 0.0;
  for (std::size_t i = 0; i < n; ++i) cumulative[i] = (c += model.weights[i]);
  double suffix = 0.0;
  for (std::size_t i = n; i-- > 0;) {
    out[i] = cumulative[i] * play_outputs[i] + suffix;
    suffix += model.weights[i] * play_outputs[i];
  }
  return out;
}

}  // namespace hystbench::compensation
