#include "hystbench/compensation/preisach_identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "details/constrained_lsq.hpp"
#include "details/preisach_smoothness.hpp"
#include "details/validate.hpp"
#include "hystbench/compensation/dead_zone.hpp"

namespace hystbench::compensation {

namespace {

// The output map's inverse S': thresholds (zero at index m) and its dead zones' columns.
struct MapDesign {
  std::vector<double> thresholds;  // 2m + 1, ascending, zero at m
  std::size_t m = 0;
  // The columns of the running sums outward, V_1..V_m above zero then below: -(dz_j - dz_(j+1)).
  void columns(double z, double* out) const noexcept {
    auto dz = [&](std::size_t i) {
      return i < thresholds.size() ? dead_zone(z, thresholds[i]) : 0.0;
    };
    for (std::size_t j = 1; j <= m; ++j) {
      out[j - 1] = -(dz(m + j) - (m + j + 1 < thresholds.size() ? dz(m + j + 1) : 0.0));
      out[m + j - 1] = -(dz(m - j) - (m >= j + 1 ? dz(m - j - 1) : 0.0));
    }
  }
};

PreisachParameters parameters_from(const PreisachParameters& grid, const MapDesign& map,
                                   const Eigen::VectorXd& x) {
  PreisachParameters p = grid;
  const auto cells = static_cast<Eigen::Index>(p.densities.size());
  for (Eigen::Index i = 0; i < cells; ++i) p.densities[static_cast<std::size_t>(i)] = x(i);
  p.slope = x(cells);
  p.offset = x(cells + 1);
  if (map.m == 0) return p;
  // The inverse map's weights from its running sums outward, then the map itself.
  std::vector<double> w(map.thresholds.size(), 0.0);
  w[map.m] = 1.0;
  double above = 0.0, below = 0.0;
  for (std::size_t j = 1; j <= map.m; ++j) {
    const double va = x(cells + 2 + static_cast<Eigen::Index>(j - 1));
    const double vb = x(cells + 2 + static_cast<Eigen::Index>(map.m + j - 1));
    w[map.m + j] = va - above;
    w[map.m - j] = vb - below;
    above = va;
    below = vb;
  }
  p.output_map = DeadZoneSuperposition({map.thresholds, w}).inverse().parameters();
  return p;
}

// The extra columns' weights in a solution (after the cells, slope, offset and map).
std::vector<double> column_weights(const Eigen::VectorXd& x, Eigen::Index first, std::size_t n) {
  std::vector<double> w(n);
  for (std::size_t j = 0; j < n; ++j) w[j] = x(first + static_cast<Eigen::Index>(j));
  return w;
}

double rms_over(std::span<const double> u, std::span<const double> y, const PreisachParameters& p,
                const PreisachFitOptions& o, std::span<const double> weights, std::size_t from,
                std::size_t to) {
  PreisachModel model(p);
  model.reset(u.front());
  double sum = 0.0;
  for (std::size_t k = 0; k < to; ++k) {
    double e = model.step(u[k]) - y[k];
    for (std::size_t j = 0; j < weights.size(); ++j) e += weights[j] * o.columns[j].values[k];
    if (k >= from) sum += e * e;
  }
  return std::sqrt(sum / static_cast<double>(to - from));
}

// The output map's inverse for m dead zones per side over the scored output's range, about its
// middle (none for m = 0).
MapDesign map_design(std::span<const double> y, std::size_t begin, std::size_t m,
                     PreisachParameters& grid) {
  MapDesign map;
  map.m = m;
  grid.center = 0.0;
  if (m == 0) return map;
  const auto [lo, hi] =
      std::minmax_element(y.begin() + static_cast<std::ptrdiff_t>(begin), y.end());
  details::require(*hi > *lo, "preisach fit: the output does not move");
  grid.center = 0.5 * (*lo + *hi);
  map.thresholds = uniform_dead_zone_thresholds(m, grid.center - *lo, *hi - grid.center);
  return map;
}

// The fit with one output map: the smoothness weight chosen on the held-out part from `split`
// on, then fitted on the whole scored record.
PreisachFit fit_with_map(std::span<const double> u, std::span<const double> y,
                         const PreisachFitOptions& o, PreisachParameters grid, std::size_t zones,
                         std::size_t split) {
  const MapDesign map = map_design(y, o.begin, zones, grid);
  const std::size_t cells = grid.densities.size(), end = u.size();
  const auto first_column = static_cast<Eigen::Index>(cells + 2 + 2 * map.m);
  const auto unknowns = first_column + static_cast<Eigen::Index>(o.columns.size());
  // One pass: each sample's cell areas, u, 1 and the map's columns, into the first part's
  // equations and the rest's.
  details::NormalEquations first(unknowns), rest(unknowns);
  PreisachModel areas(grid);
  areas.reset(u.front());
  std::vector<double> row(cells);
  for (std::size_t k = 0; k < end; ++k) {
    areas.cell_areas(u[k], row);
    areas.step(u[k]);
    if (k < o.begin) continue;
    details::NormalEquations& ne = k < split ? first : rest;
    double* r = ne.row();
    std::copy(row.begin(), row.end(), r);
    r[cells] = u[k];
    r[cells + 1] = 1.0;
    const double z = y[k] - grid.center;
    map.columns(z, r + cells + 2);
    for (std::size_t j = 0; j < o.columns.size(); ++j) r[first_column + j] = o.columns[j].values[k];
    ne.push(z);
  }
  Eigen::VectorXd lower = Eigen::VectorXd::Zero(unknowns);
  const Eigen::VectorXd upper =
      Eigen::VectorXd::Constant(unknowns, std::numeric_limits<double>::infinity());
  lower(static_cast<Eigen::Index>(cells) + 1) = -std::numeric_limits<double>::infinity();  // offset
  for (Eigen::Index j = static_cast<Eigen::Index>(cells) + 2; j < first_column; ++j) {
    lower(j) = kMinMapSlope - 1.0;  // the inverse map's slope outward >= kMinMapSlope
  }
  for (std::size_t j = 0; j < o.columns.size(); ++j) {
    if (!o.columns[j].nonnegative) {
      lower(first_column + static_cast<Eigen::Index>(j)) = -std::numeric_limits<double>::infinity();
    }
  }
  const Eigen::MatrixXd& g_first = first.gram();
  PreisachFit fit;
  auto solve = [&](const Eigen::MatrixXd& g, const Eigen::VectorXd& b, double weight) {
    // The penalty scaled by the first part's columns, for the whole record's fit too.
    const double scale = g_first.diagonal().head(static_cast<Eigen::Index>(cells)).mean() /
                         g.diagonal().head(static_cast<Eigen::Index>(cells)).mean();
    Eigen::MatrixXd penalised = g;
    details::add_preisach_smoothness(penalised, grid.cells, 0, weight * scale);
    const Eigen::VectorXd x = details::solve_bounded_lsq(penalised, b, lower, upper).x;
    fit.column_weights = column_weights(x, first_column, o.columns.size());
    return parameters_from(grid, map, x);
  };
  fit.heldout_rms = std::numeric_limits<double>::infinity();
  for (const double s : o.smoothness) {
    const PreisachParameters p = solve(g_first, first.rhs(), s);
    const double rms = rms_over(u, y, p, o, fit.column_weights, split, end);
    fit.tried_rms.push_back(rms);
    if (rms < fit.heldout_rms) {
      fit.smoothness = s;
      fit.heldout_rms = rms;
    }
  }
  fit.parameters = solve(g_first + rest.gram(), first.rhs() + rest.rhs(), fit.smoothness);
  fit.fit_rms = rms_over(u, y, fit.parameters, o, fit.column_weights, o.begin, end);
  fit.output_zones = zones;
  return fit;
}

}  // namespace

PreisachFit fit_preisach(std::span<const double> u, std::span<const double> y,
                         const PreisachFitOptions& o) {
  details::require(u.size() == y.size(), "preisach fit: u and y differ in length");
  details::require_finite(u, "u");
  details::require_finite(y, "y");
  details::require(o.heldout_fraction > 0.0 && o.heldout_fraction <= 0.5,
                   "preisach fit: heldout_fraction must be in (0, 0.5]");
  details::require(!o.smoothness.empty() && !o.output_zones.empty(),
                   "preisach fit: no smoothness weight or output map to try");
  for (const PreisachFitOptions::Column& c : o.columns) {
    details::require(c.values.size() == u.size(), "preisach fit: a column differs in length");
    details::require_finite(c.values, "a column");
  }
  for (const double s : o.smoothness) {
    details::require(std::isfinite(s) && s >= 0.0, "preisach fit: smoothness weights must be >= 0");
  }
  const std::size_t n = o.cells, cells = PreisachModel::cell_count(n);
  details::require(n >= 1 && n <= PreisachModel::kMaxCells, "preisach fit: cells out of range");
  details::require(o.begin < u.size() && u.size() - o.begin >= 4 * (cells + 2),
                   "preisach fit: the record is too short for " + std::to_string(cells) +
                       " cells (at least 4 samples per unknown after `begin`)");
  PreisachParameters grid{o.u_min, o.u_max, n, std::vector<double>(cells, 0.0), 0.0, 0.0};
  if (!(o.u_min < o.u_max)) {
    const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
    grid.u_min = *lo;
    grid.u_max = *hi;
    details::require(grid.u_min < grid.u_max, "preisach fit: the input does not move");
  }
  const auto split = u.size() - static_cast<std::size_t>(o.heldout_fraction *
                                                         static_cast<double>(u.size() - o.begin));
  PreisachFit best;
  for (const std::size_t zones : o.output_zones) {
    PreisachFit fit = fit_with_map(u, y, o, grid, zones, split);
    if (best.tried_rms.empty() || fit.heldout_rms < best.heldout_rms) best = std::move(fit);
  }
  return best;
}

}  // namespace hystbench::compensation
