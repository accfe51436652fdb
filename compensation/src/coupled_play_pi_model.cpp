#include "hystbench/compensation/coupled_play_pi_model.hpp"

#include <algorithm>
#include <string>

#include "details/play_kernels.hpp"
#include "details/validate.hpp"

namespace hystbench::compensation {

CoupledPlayPiModel::CoupledPlayPiModel(CoupledPlayParameters p)
    : p_(std::move(p)),
      dz_(p_.has_dead_zones() ? DeadZoneSuperposition(p_.dead_zone) : DeadZoneSuperposition()),
      z_(p_.weights.size(), 0.0) {
  const std::size_t n = p_.weights.size();
  details::require(n > 0, "coupled_play.weights must not be empty");
  const std::pair<const std::vector<double>*, const char*> blocks[] = {{&p_.r, "coupled_play.r"},
                                                                       {&p_.ra, "coupled_play.ra"},
                                                                       {&p_.rb, "coupled_play.rb"},
                                                                       {&p_.rc, "coupled_play.rc"}};
  for (const auto& [v, name] : blocks) {
    details::require_same_size(v->size(), n, name, "coupled_play.weights");
    details::require_finite(*v, name);
    for (std::size_t i = 0; i < n; ++i) {
      details::require((*v)[i] >= 0.0,
                       std::string(name) + "[" + std::to_string(i) + "] must be >= 0");
    }
  }
  details::require_finite(p_.weights, "coupled_play.weights");
  details::require_finite(p_.offset, "coupled_play.offset");
  details::require_finite(p_.center, "deadzone.center");
}

double CoupledPlayPiModel::operator_output(double u, double u_prev, double z_prev, double r,
                                           double ra, double rb, double rc) noexcept {
  if (u >= u_prev) {
    const double width = u >= rc ? r : rc;
    return std::max(z_prev, u - width);
  }
  const double width = u <= -rb ? ra : rb;
  return std::min(z_prev, u + width);
}

namespace {

details::CoupledPlayArrays arrays(const CoupledPlayParameters& p) noexcept {
  return {p.r.data(), p.ra.data(), p.rb.data(), p.rc.data(), p.weights.data(), p.weights.size()};
}

}  // namespace

double CoupledPlayPiModel::step(double u) noexcept {
  const double v = p_.offset + details::coupled_play_step(u, u >= u_prev_, arrays(p_), z_.data());
  u_prev_ = u;
  return output(v);
}

double CoupledPlayPiModel::peek(double u) const noexcept {
  return output(p_.offset + details::coupled_play_peek(u, u >= u_prev_, arrays(p_), z_.data()));
}

void CoupledPlayPiModel::reset(double u0) noexcept {
  std::fill(z_.begin(), z_.end(), u0);
  u_prev_ = u0;
}

Invertibility CoupledPlayPiModel::invertibility() const {
  // Each operator's branches are non-decreasing in u only if its width never shrinks when the
  // input crosses a switching level: rc >= r on the rising side, ra <= rb on the falling side.
  for (std::size_t i = 0; i < p_.weights.size(); ++i) {
    if (p_.rc[i] < p_.r[i] || p_.ra[i] > p_.rb[i]) {
      Invertibility v;
      v.invertible = false;
      v.block = "coupled_play";
      v.index = static_cast<int>(i);
      v.value = p_.rc[i] < p_.r[i] ? p_.rc[i] - p_.r[i] : p_.rb[i] - p_.ra[i];
      v.reason = "coupled-play operator " + std::to_string(i) +
                 " is not monotone (needs rc >= r and ra <= rb)";
      return v;
    }
  }
  // An operator that jumps (rc > r: up when a rising input crosses rc; ra < rb: down when a
  // falling one crosses -rb) moves the output against the input if its weight is negative.
  for (std::size_t i = 0; i < p_.weights.size(); ++i) {
    if ((p_.rc[i] > p_.r[i] || p_.ra[i] < p_.rb[i]) && p_.weights[i] < 0.0) {
      Invertibility v;
      v.invertible = false;
      v.block = "coupled_play";
      v.index = static_cast<int>(i);
      v.value = p_.weights[i];
      v.reason = "coupled-play operator " + std::to_string(i) +
                 " jumps (rc > r or ra < rb) with a negative weight: its jump lowers the output";
      return v;
    }
  }
  Invertibility v = check_cumulative_weights(p_.weights.data(), p_.weights.size(), "coupled_play",
                                             "cumulative coupled-play weight");
  if (!v.invertible) return v;
  return dz_.invertibility();
}

std::unique_ptr<HysteresisModel> CoupledPlayPiModel::clone() const {
  return std::make_unique<CoupledPlayPiModel>(*this);
}

}  // namespace hystbench::compensation
