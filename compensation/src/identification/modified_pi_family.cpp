// The modified PI family (Kuhnen's error model): its dead zones and plays by held-out error.
#include <algorithm>
#include <vector>

#include "details/identifier.hpp"

namespace hystbench::compensation::details::identification {

int Identifier::mpi_plays(int m) {
  return pick(operator_grid(2 * m),
              [&](int n) { return memo(ModelKind::kModifiedPi, n, m).score(); });
}

Candidate Identifier::search_mpi() {
  if (best_mpi_) return *best_mpi_;
  const std::vector<int> ms = dead_zone_grid();
  int m = ms.size() == 1 ? ms.front() : std::min(kDefaultDeadZones, ms.back());
  int n = mpi_plays(m);
  if (ms.size() > 1) {
    const int m2 = pick(ms, [&](int mm) { return memo(ModelKind::kModifiedPi, n, mm).score(); });
    if (m2 != m) n = mpi_plays(m = m2);
  }
  best_mpi_ = memo(ModelKind::kModifiedPi, n, m);
  return *best_mpi_;
}

}  // namespace hystbench::compensation::details::identification
