#include "hystbench/compensation/preisach_identification.hpp"

#include <algorithm>
#include <cmath>

#include "details/preisach_search.hpp"
#include "details/record_startup.hpp"
#include "details/validate.hpp"

namespace hystbench::compensation {

PreisachFit fit_preisach(std::span<const double> u, std::span<const double> y,
                         const PreisachFitOptions& o) {
  details::require(u.size() == y.size(), "preisach fit: u and y differ in length");
  details::require_finite(u, "u");
  details::require_finite(y, "y");
  details::require(o.heldout_fraction > 0.0 && o.heldout_fraction <= 0.5,
                   "preisach fit: heldout_fraction must be in (0, 0.5]");
  details::require(!o.smoothness.empty() && !o.output_zones.empty(),
                   "preisach fit: no smoothness weight or output map to try");
  for (const double s : o.smoothness) {
    details::require(std::isfinite(s) && s >= 0.0, "preisach fit: smoothness weights must be >= 0");
  }
  const std::size_t n = o.cells, cells = PreisachModel::cell_count(n);
  details::require(n >= 1 && n <= PreisachModel::kMaxCells, "preisach fit: cells out of range");
  const auto heldout = static_cast<std::size_t>(o.heldout_fraction * static_cast<double>(u.size()));
  const std::size_t begin =
      o.begin ? *o.begin
              : details::startup_samples(u.first(u.size() - heldout), (u.size() - heldout) / 4);
  details::require(begin < u.size() && u.size() - begin >= 4 * (cells + 2),
                   "preisach fit: the record is too short for " + std::to_string(cells) +
                       " cells (at least 4 samples per unknown after `begin`)");
  double u_min = o.u_min, u_max = o.u_max;
  if (!(u_min < u_max)) {
    const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
    u_min = *lo;
    u_max = *hi;
    details::require(u_min < u_max, "preisach fit: the input does not move");
  }
  const auto split = u.size() - static_cast<std::size_t>(o.heldout_fraction *
                                                         static_cast<double>(u.size() - begin));
  details::ModelStructure base;
  base.kind = ModelKind::kPreisach;
  base.dt = 1.0;  // no lags or drift: the sampling does not enter
  base.preisach_cells = n;
  base.plane_min = u_min;
  base.plane_max = u_max;
  base.input_reference = 0.5 * (u_min + u_max);
  base.min_dead_zone_slope = kMinMapSlope;
  const details::PreisachSearch found =
      details::search_preisach(base, u, y, begin, split, u.size(), o.smoothness, o.output_zones);
  const details::Design design(found.structure);
  PreisachFit fit;
  fit.parameters =
      dynamic_cast<const PreisachModel&>(design.build(found.x).hysteresis()).parameters();
  fit.smoothness = found.structure.smoothness;
  fit.output_zones = found.structure.dead_zone_thresholds.size() / 2;
  fit.heldout_rms = found.heldout_rms;
  fit.begin = begin;
  fit.tried_rms = found.tried_rms;
  PreisachModel model(fit.parameters);
  model.reset(u.front());
  double sum = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double e = model.step(u[k]) - y[k];
    if (k >= begin) sum += e * e;
  }
  fit.fit_rms = std::sqrt(sum / static_cast<double>(u.size() - begin));
  return fit;
}

}  // namespace hystbench::compensation
