#include "hystbench/common/fit_families.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>

namespace hystbench::common {

namespace hc = compensation;

namespace {
constexpr std::array kFamilies{hc::ModelKind::kPi, hc::ModelKind::kModifiedPi,
                               hc::ModelKind::kCoupledPlayPi, hc::ModelKind::kRateDependentPi,
                               hc::ModelKind::kPreisach};
constexpr const char* kAuto = "auto";
}  // namespace

std::span<const hc::ModelKind> fit_families() noexcept { return kFamilies; }

std::string fit_family_names() {
  std::string names;
  for (const hc::ModelKind k : kFamilies) names += std::string(hc::to_string(k)) + ", ";
  return names + kAuto;
}

std::vector<std::string> fit_family_name_list() {
  std::vector<std::string> names;
  names.reserve(kFamilies.size() + 1);
  for (const hc::ModelKind k : kFamilies) names.emplace_back(hc::to_string(k));
  names.emplace_back(kAuto);
  return names;
}

namespace {
// A fitted family's kind by its name (a model kind that is no fit family: none).
std::optional<hc::ModelKind> family_named(const std::string& name) noexcept {
  const auto kind = hc::model_kind_from_string(name);
  if (kind && std::find(kFamilies.begin(), kFamilies.end(), *kind) != kFamilies.end()) return kind;
  return std::nullopt;
}
}  // namespace

bool is_fit_family(const std::string& name) noexcept {
  return name == kAuto || family_named(name).has_value();
}

std::optional<hc::ModelKind> parse_fit_family(const std::string& name) {
  if (name == kAuto) return std::nullopt;
  if (const auto kind = family_named(name)) return kind;
  throw std::invalid_argument("unknown '" + name + "' (" + fit_family_names() + ")");
}

}  // namespace hystbench::common
