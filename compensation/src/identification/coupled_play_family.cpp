// The coupled-play PI family: the modified PI's order, then the asymmetry scales on a grid,
// kept only where they beat the modified PI they extend.
#include <array>
#include <memory>
#include <vector>

#include "details/identifier.hpp"
#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"

namespace hystbench::compensation::details::identification {

namespace {

// Coupled-play asymmetry grid: rb (and ra) and rc as multiples of r. The levels compare with
// the absolute input (the paper's is bipolar): for u >= 0 the falling width is always rb, and
// rc only changes anything when rc > r + rb, hence level scales up to 6.
// Monotone (invertible) operators need rc >= r and ra <= rb.
constexpr double kCpWidthScales[] = {0.5, 0.7, 1.0, 1.4, 2.0};
constexpr double kCpLevelScales[] = {1.0, 2.0, 3.0, 4.0, 6.0};

}  // namespace

Candidate Identifier::search_cpi() {
  // Plain plays are coupled plays with unit scales: choose the order there, then the scales.
  // The output dead zones (the modified PI's stage) are chosen with the plays by search_mpi():
  // with unit scales the coupled-play model is that modified PI, so the scales only add.
  // Without dead zones (--dead-zones 0) it is the paper's model on the classical PI's order.
  const std::vector<int> ns = operator_grid(0);
  int n = ns.size() == 1 ? ns.front() : 0;
  int m = 0;
  if (o_.dead_zones != 0) {
    const Candidate mpi = search_mpi();
    m = dead_zones_of(mpi.structure);
    if (n == 0) n = static_cast<int>(mpi.structure.plays());
  }
  if (n == 0) n = static_cast<int>(search_pi().structure.plays());
  std::vector<std::array<double, 3>> grid;
  const bool bipolar = r_.u_lo < 0.0;
  for (const double kb : kCpWidthScales) {
    for (const double kc : kCpLevelScales) {
      if (bipolar) {
        for (const double ka : kCpWidthScales) {
          if (ka <= kb) grid.push_back({ka, kb, kc});
        }
      } else {
        grid.push_back({kb, kb, kc});  // ra only acts below -rb: irrelevant for u >= 0
      }
    }
  }
  // Unit scales first: asymmetry must beat the plain plays by the parsimony margin, as a larger
  // order must. On a symmetric actuator scales chosen on a gain within the noise change from one
  // record to the next, and the tracking with them.
  grid.insert(grid.begin(), {1.0, 1.0, 1.0});
  std::size_t done = 0;
  const std::array<double, 3> cp = pick(grid, [&](const std::array<double, 3>& k) {
    stage_progress(static_cast<double>(done++) / static_cast<double>(grid.size()),
                   "coupled-play asymmetry scales");
    return memo(ModelKind::kCoupledPlayPi, n, m, k).score();
  });
  return memo(ModelKind::kCoupledPlayPi, n, m, cp);
}

Candidate Identifier::nested_cpi(const Candidate& mpi) {
  // The MPI as coupled plays with unit scales (no asymmetry): the same outputs and scores.
  const auto& h = dynamic_cast<const ModifiedPiModel&>(mpi.model->hysteresis());
  const ModifiedPiParameters& p = h.parameters();
  Candidate c = mpi;
  c.structure.kind = ModelKind::kCoupledPlayPi;
  c.structure.cp_scale = {1.0, 1.0, 1.0};
  const std::vector<double>& r = p.play.thresholds;
  ActuatorModel m(std::make_unique<CoupledPlayPiModel>(
      CoupledPlayParameters{r, r, r, r, p.play.weights, p.play.offset, p.dead_zone, p.center}));
  finish_nested(c, std::move(m), mpi,
                " (unit scales: no asymmetry beat the modified PI it extends)");
  return c;
}

void Identifier::check_cpi_nesting(Candidate& best) {
  if (!best.structure.has_dead_zones() ||
      best.structure.cp_scale == std::array<double, 3>{1.0, 1.0, 1.0}) {
    return;
  }
  // Nesting, as for the order: the asymmetry must beat the modified PI it extends (refined
  // and with creep alike) by the parsimony margin. An asymmetry that gains nothing once both
  // are refined varies from record to record, and the tracking with it.
  progress(0.93, "checking the asymmetry against the modified PI it extends");
  Candidate mpi = search_mpi();
  finish(mpi);
  if (best.score() > mpi.score() * (1.0 - kParsimony)) {
    best = o_.kind ? nested_cpi(mpi) : std::move(mpi);
  }
}

}  // namespace hystbench::compensation::details::identification
