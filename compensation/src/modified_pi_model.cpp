#include "hystbench/compensation/modified_pi_model.hpp"

#include "details/validate.hpp"

namespace hystbench::compensation {

ModifiedPiModel::ModifiedPiModel(ModifiedPiParameters p)
    : p_(std::move(p)), pi_(p_.play), dz_(p_.dead_zone) {
  details::require_finite(p_.center, "deadzone.center");
}

double ModifiedPiModel::step(double u) noexcept {
  return p_.center + dz_.apply(pi_.step(u) - p_.center);
}

double ModifiedPiModel::peek(double u) const noexcept {
  return p_.center + dz_.apply(pi_.peek(u) - p_.center);
}

std::size_t ModifiedPiModel::operator_count() const noexcept {
  return pi_.operator_count() + dz_.size();
}

Invertibility ModifiedPiModel::invertibility() const {
  Invertibility v = pi_.invertibility();
  if (!v.invertible) return v;
  return dz_.invertibility();
}

std::unique_ptr<HysteresisModel> ModifiedPiModel::clone() const {
  return std::make_unique<ModifiedPiModel>(*this);
}

}  // namespace hystbench::compensation
