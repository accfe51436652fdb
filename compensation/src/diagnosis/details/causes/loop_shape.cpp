// Candidate `loop_shape`: the baseline's operators cannot follow the loop's shape (a relay
// density that varies over the Preisach plane, a saturating top), whatever their weights.
// Statistic: the share of the baseline residual's variance that a coarse Preisach plane of the
// input (kProbeCells per side, free signed densities, a slope and an offset) explains on the fit
// part: a rate-independent memory function of the input, which is what any hysteresis operator
// could add. Extension: the operator swapped for a nonparametric Preisach plane (smoothness
// penalty), the output map the identity or dead zones (whichever simulates the fit part best);
// the baseline's creep lags, delay and dynamics kept and refitted with it. A baseline that is a
// plane already has nothing to swap (statistic 0).
#include <algorithm>
#include <array>
#include <string>

#include "details/constrained_lsq.hpp"
#include "diagnosis/details/baseline.hpp"
#include "diagnosis/details/candidates.hpp"
#include "hystbench/compensation/preisach_identification.hpp"

namespace hystbench::compensation::details {

namespace {

constexpr double kLoopShapeThreshold = 0.15;
// The probe's cells per side: coarse, so that its few unknowns cannot take the noise.
constexpr std::size_t kProbeCells = 8;
// The extension's plane: cells per side, and its smoothness weight relative to the columns'
// mean square (the fit's middle choice; the held-out blocks are the diagnosis's to score).
constexpr std::size_t kPlaneCells = 20;
constexpr double kSmoothness = 1e-4;
// Output maps tried: dead zones per side (0: the identity).
constexpr std::array<int, 2> kOutputZones{0, 3};
constexpr double kLoopShapeParsimony = 0.02;

ModelStructure plane_of(const ModelStructure& base, const DiagnosisRecord& r, std::size_t cells,
                        int zones) {
  ModelStructure s;
  s.kind = ModelKind::kPreisach;
  s.dt = base.dt;
  s.creep_time_constants = base.creep_time_constants;
  s.drift = base.drift;
  s.drift_t0_s = base.drift_t0_s;
  s.preisach_cells = cells;
  s.plane_min = r.u_lo;
  s.plane_max = r.u_hi;
  s.input_reference = 0.5 * (r.u_lo + r.u_hi);
  s.smoothness = kSmoothness;
  s.min_dead_zone_slope = kMinMapSlope;
  if (zones > 0) {
    s.center = 0.5 * (r.y_lo + r.y_hi);
    s.dead_zone_thresholds = uniform_dead_zone_thresholds(static_cast<std::size_t>(zones),
                                                          s.center - r.y_lo, r.y_hi - s.center);
  }
  return s;
}

// Share of the residual's variance over the fit part's search rows that the probe plane's
// columns explain (unconstrained least squares), 0..1.
double explained_by_probe(const CandidateContext& c) {
  const DiagnosisRecord& r = c.record;
  Design probe(plane_of(c.base.structure, r, kProbeCells, 0));
  const std::vector<double> ud = delayed(r.u, c.base.delay_samples);
  NormalEquations ne(probe.unknowns());
  double sum = 0.0;
  probe.reset(ud[0]);
  for (std::size_t k = 0; k < r.n; ++k) {
    const bool use = r.fit_row(k) && k % r.search_stride == 0;
    if (!use) {
      probe.skip(ud[k]);
      continue;
    }
    probe.row(ud[k], 0.0, ne.row());
    ne.push(c.residual[k]);
    sum += c.residual[k];
  }
  const auto rows = static_cast<double>(ne.rows());
  if (rows <= static_cast<double>(probe.unknowns())) return 0.0;
  const double total = ne.target_square_sum() - sum * sum / rows;
  if (!(total > 0.0)) return 0.0;
  const Eigen::VectorXd x = ne.gram().ldlt().solve(ne.rhs());
  const double left = ne.target_square_sum() - ne.rhs().dot(x);
  return std::clamp(1.0 - left / total, 0.0, 1.0);
}

}  // namespace

CandidateOutcome test_loop_shape(const CandidateContext& c) {
  CandidateOutcome out;
  out.threshold = kLoopShapeThreshold;
  if (c.base.structure.kind == ModelKind::kPreisach || !c.swap_operator) {
    out.evidence = c.swap_operator
                       ? "the baseline is a Preisach plane already: no operator to swap"
                       : "not tested: the baseline's family is kept (a family given, or the "
                         "classical PI identified here)";
    out.fit = c.base_fit;
    out.extension = "none (the baseline's operators)";
    return out;
  }
  out.statistic = explained_by_probe(c);
  out.evidence = "a Preisach plane of the input (" + std::to_string(kProbeCells) + " x " +
                 std::to_string(kProbeCells) + " cells) explains " + percent(out.statistic) +
                 " of the residual variance: the operators miss the loop's shape";
  std::vector<ExtensionFit> fits;
  for (const int zones : kOutputZones) {
    ExtensionSpec spec = c.base;
    spec.structure = plane_of(c.base.structure, c.record, kPlaneCells, zones);
    fits.push_back(fit_extension(c.record, spec));
  }
  const std::size_t kept = simplest_within(fits, kLoopShapeParsimony);
  out.fit = std::move(fits[kept]);
  const int zones = kOutputZones[kept];
  out.extension =
      "the operators swapped for a Preisach plane (" + std::to_string(kPlaneCells) + " x " +
      std::to_string(kPlaneCells) + " cells" +
      (zones > 0 ? ", " + std::to_string(zones) + " output dead zones per side" : std::string()) +
      ")";
  // What is tested on top of the plane keeps its cells' shape as fitted here, their scale and the
  // output map free (as for a plane given as the baseline): a search over a mode or a delay would
  // refit hundreds of cells at every trial otherwise.
  const bool drift = out.fit.spec.drift;
  out.fit.spec = spec_of_model(out.fit.model, c.record);
  out.fit.spec.drift = drift;
  return out;
}

std::optional<ExtensionFit> refit_plane_cells(const DiagnosisRecord& r, const ExtensionFit& joint) {
  const ModelStructure& s = joint.spec.structure;
  if (s.kind != ModelKind::kPreisach || s.preisach_shape.empty()) return std::nullopt;
  ExtensionSpec spec = joint.spec;
  spec.structure.preisach_shape.clear();
  spec.structure.smoothness = kSmoothness;
  spec.structure.min_dead_zone_slope = kMinMapSlope;
  ExtensionFit free = fit_extension(r, spec);
  if (!(free.fit.rmse < joint.fit.rmse)) return std::nullopt;
  return free;
}

}  // namespace hystbench::compensation::details
