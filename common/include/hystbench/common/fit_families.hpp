#pragma once
// The hysteresis families a fit may ask for by name ("pi", "mpi", "cpi", "rpi") and "auto"
// (every family, the best one chosen): one list for identify, `hystbench fit` and the candidates
// identify verifies. Not real-time safe.
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/hysteresis_model.hpp"

namespace hystbench::common {

/// Every family, in the order "auto" fits and reports them.
std::span<const compensation::ModelKind> fit_families() noexcept;
/// "pi, mpi, cpi, rpi, auto": the names a request or option may give.
std::string fit_family_names();
/// The same names as a list, for option and key checks.
std::vector<std::string> fit_family_name_list();
/// True for a family's name or "auto".
bool is_fit_family(const std::string& name) noexcept;
/// The family named, or nullopt for "auto" (every family); throws std::invalid_argument
/// "unknown 'name' (pi, mpi, cpi, rpi, auto)" for anything else.
std::optional<compensation::ModelKind> parse_fit_family(const std::string& name);

}  // namespace hystbench::common
