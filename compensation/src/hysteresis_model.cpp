#include "hystbench/compensation/hysteresis_model.hpp"

#include <array>
#include <limits>
#include <utility>

namespace hystbench::compensation {

namespace {
constexpr std::array<std::pair<ModelKind, std::string_view>, 5> kNames{{
    {ModelKind::kPi, "pi"},
    {ModelKind::kModifiedPi, "mpi"},
    {ModelKind::kCoupledPlayPi, "cpi"},
    {ModelKind::kRateDependentPi, "rpi"},
    {ModelKind::kPreisach, "preisach"},
}};
}  // namespace

double HysteresisModel::rate_for_output(double /*u*/, double /*y*/) const noexcept {
  return std::numeric_limits<double>::quiet_NaN();
}

std::string_view to_string(ModelKind kind) noexcept {
  for (const auto& [k, name] : kNames) {
    if (k == kind) return name;
  }
  return "unknown";
}

std::optional<ModelKind> model_kind_from_string(std::string_view name) noexcept {
  for (const auto& [k, n] : kNames) {
    if (n == name) return k;
  }
  return std::nullopt;
}

std::vector<double> HysteresisModel::simulate(std::span<const double> u) {
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = step(u[k]);
  return y;
}

}  // namespace hystbench::compensation
