#include "hystbench/compensation/rate_dependent_pi_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "details/validate.hpp"

namespace hystbench::compensation {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

RateDependentPiModel::RateDependentPiModel(RateDependentPiParameters p, double dt_s)
    : p_(std::move(p)), pi_(p_.base.play), dz_(p_.base.dead_zone) {
  if (dz_.invertibility().invertible) dz_inverse_ = dz_.inverse();
  details::require_same_size(p_.rate_coefficients.size(), p_.base.play.weights.size(),
                             "rate.coefficients", "play.weights");
  details::require_finite(p_.rate_coefficients, "rate.coefficients");
  details::require_finite(p_.max_rate, "rate.max_rate");
  details::require(p_.max_rate >= 0.0, "rate.max_rate must be >= 0");
  details::require_finite(p_.rate_filter_s, "rate.filter_s");
  details::require(p_.rate_filter_s >= 0.0, "rate.filter_s must be >= 0");
  details::require_finite(p_.record_max_rate, "rate.record_max_rate");
  details::require(p_.record_max_rate >= 0.0, "rate.record_max_rate must be >= 0");
  details::require_finite(p_.base.center, "deadzone.center");
  details::require_finite(p_.threshold_rate_s, "rate.threshold_s");
  details::require(p_.threshold_rate_s >= 0.0, "rate.threshold_s must be >= 0");
  details::require_finite(p_.threshold_rate_exponent, "rate.threshold_exponent");
  details::require(p_.threshold_rate_exponent > 0.0 && p_.threshold_rate_exponent <= 1.0,
                   "rate.threshold_exponent must be in (0, 1]");
  details::require(p_.threshold_rate_exponent == 1.0 ||
                       (p_.rate_law == RateLaw::kThresholds && p_.max_rate > 0.0),
                   "rate.threshold_exponent below 1 is only for the thresholds law "
                   "(rate.law = \"thresholds\") with rate.max_rate > 0");
  if (p_.rate_law == RateLaw::kThresholds) {
    details::require(std::all_of(p_.rate_coefficients.begin(), p_.rate_coefficients.end(),
                                 [](double c) { return c == 0.0; }),
                     "rate.coefficients must be 0 with the thresholds law (its weights are "
                     "rate-free)");
  } else {
    details::require(p_.threshold_rate_s == 0.0,
                     "rate.threshold_s is only for the thresholds law (rate.law = \"thresholds\")");
  }
  dw_.resize(p_.rate_coefficients.size());
  double prev = 0.0;
  for (std::size_t i = 0; i < dw_.size(); ++i) {
    dw_[i] = p_.rate_coefficients[i] - prev;
    prev = p_.rate_coefficients[i];
  }
  set_sample_period(dt_s);
}

void RateDependentPiModel::set_sample_period(double dt_s) {
  details::require(std::isfinite(dt_s) && dt_s > 0.0, "sample period must be > 0");
  dt_ = dt_s;
  rate_.configure(p_.rate_filter_s, dt_, p_.rate_law);
}

double RateDependentPiModel::capped(double rate) const noexcept {
  // Capped at the identified range: beyond it the linear law is an extrapolation.
  if (!(p_.max_rate > 0.0)) return rate;
  return std::clamp(rate, p_.rate_law == RateLaw::kSigned ? -p_.max_rate : 0.0, p_.max_rate);
}

double RateDependentPiModel::evaluate(double u, double rate, double* state_out) const noexcept {
  const auto& r = p_.base.play.thresholds;
  const auto& w = p_.base.play.weights;
  const double* s = pi_.state().data();
  double y = p_.base.play.offset;
  // 0 unless the thresholds law.
  const double widen =
      threshold_widening(p_.threshold_rate_s, p_.threshold_rate_exponent, p_.max_rate, rate);
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double ri = r[i] > 0.0 ? r[i] + widen : 0.0;  // the linear term does not lag
    const double pl = std::max(u - ri, std::min(u + ri, s[i]));
    if (state_out != nullptr) state_out[i] = pl;
    y += (w[i] + dw_[i] * rate) * pl;
  }
  return p_.base.center + dz_.apply(y - p_.base.center);
}

double RateDependentPiModel::rate_for_output(double u, double y) const noexcept {
  if (!dz_inverse_ || p_.rate_law == RateLaw::kThresholds) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  const auto& r = p_.base.play.thresholds;
  const auto& w = p_.base.play.weights;
  const double* s = pi_.state().data();
  double at_rest = p_.base.play.offset, per_rate = 0.0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double pl = std::max(u - r[i], std::min(u + r[i], s[i]));
    at_rest += w[i] * pl;
    per_rate += dw_[i] * pl;
  }
  const double wanted = p_.base.center + dz_inverse_->apply(y - p_.base.center) - at_rest;
  if (p_.rate_law == RateLaw::kSigned) {
    if (per_rate == 0.0) return wanted == 0.0 ? 0.0 : std::copysign(kInf, wanted);
    return wanted / per_rate;
  }
  if (wanted <= 0.0) return 0.0;
  if (!(per_rate > 0.0)) return kInf;
  return wanted / per_rate;
}

double RateDependentPiModel::step(double u) noexcept {
  return evaluate(u, capped(rate_.step(u)), pi_.mutable_state().data());
}

double RateDependentPiModel::peek(double u) const noexcept {
  return evaluate(u, capped(rate_.peek(u)), nullptr);
}

double RateDependentPiModel::peek_at_rate(double u, double rate) const noexcept {
  return evaluate(u, capped(rate), nullptr);
}

void RateDependentPiModel::reset(double u0) noexcept {
  pi_.reset(u0);
  rate_.reset(u0);
}

bool RateDependentPiModel::rate_free() const noexcept {
  return p_.threshold_rate_s == 0.0 &&
         std::all_of(dw_.begin(), dw_.end(), [](double d) { return d == 0.0; });
}

bool RateDependentPiModel::grows_with_signed_rate() const noexcept {
  return p_.rate_law == RateLaw::kSigned &&
         std::all_of(dw_.begin(), dw_.end(), [](double d) { return d >= 0.0; });
}

std::optional<ThresholdsRateLaw> RateDependentPiModel::thresholds_law() const {
  if (p_.rate_law != RateLaw::kThresholds) return std::nullopt;
  return ThresholdsRateLaw{p_.threshold_rate_s, p_.threshold_rate_exponent, p_.max_rate,
                           p_.record_max_rate, p_.rate_filter_s};
}

std::unique_ptr<HysteresisModel> RateDependentPiModel::rate_free_part() const {
  return std::make_unique<ModifiedPiModel>(p_.base);
}

std::size_t RateDependentPiModel::operator_count() const noexcept {
  return pi_.operator_count() + dz_.size();
}

Invertibility RateDependentPiModel::invertibility() const {
  // W_i(rate) is linear in rate, so positivity on [0 or -max_rate, max_rate] is checked at both
  // ends (and at 0, the law's own rest).
  const double lowest = p_.rate_law == RateLaw::kSigned ? -p_.max_rate : 0.0;
  for (const double rate : {0.0, p_.max_rate, lowest}) {
    Invertibility v = check_cumulative_weights(p_.base.play.weights.data(), dw_.size(), "rate",
                                               "cumulative play weight", rate, dw_.data());
    if (!v.invertible) return v;
  }
  if (p_.base.play.thresholds.front() != 0.0) return pi_.invertibility();
  return dz_.invertibility();
}

std::unique_ptr<HysteresisModel> RateDependentPiModel::clone() const {
  return std::make_unique<RateDependentPiModel>(*this);
}

}  // namespace hystbench::compensation
