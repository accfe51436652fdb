// Candidate `asymmetry`: the loops are not point-symmetric, which a classical PI cannot
// represent. Statistic: share of the baseline residual variance explained by the input level
// (rising and falling passes pooled, so direction-dependent errors cancel). Extension: the
// baseline's plays with dead zones (modified PI, 1..3 per side) or coupled plays, whichever
// simulates the fit part best.
#include <algorithm>
#include <limits>

#include "diagnosis/details/candidates.hpp"

namespace hystbench::compensation::details {

namespace {

constexpr double kAsymmetryThreshold = 0.15;
constexpr double kAsymmetryParsimony = 0.02;
// Coupled-play scales (rb = ra, rc) tried for unipolar inputs; bipolar inputs add ra < rb.
constexpr std::array<std::array<double, 3>, 4> kCoupledScales{
    {{0.6, 0.6, 2.0}, {1.5, 1.5, 2.0}, {0.6, 0.6, 4.0}, {1.5, 1.5, 4.0}}};

ModelStructure with_dead_zones(const ModelStructure& base, const DiagnosisRecord& r, int m) {
  ModelStructure s = base;
  // A Preisach plane keeps its relays and gains dead zones on its output map.
  if (s.kind != ModelKind::kRateDependentPi && s.kind != ModelKind::kPreisach) {
    s.kind = ModelKind::kModifiedPi;
  }
  s.center = 0.5 * (r.y_lo + r.y_hi);
  const double above = r.y_hi - s.center;
  const double below = s.center - r.y_lo;
  s.dead_zone_thresholds = uniform_dead_zone_thresholds(static_cast<std::size_t>(m), below, above);
  return s;
}

std::string family_name(ModelKind kind) {
  switch (kind) {
    case ModelKind::kRateDependentPi:
      return "rate-dependent PI";
    case ModelKind::kPreisach:
      return "Preisach plane";
    default:
      return "modified PI";
  }
}

int dead_zones_per_side(const ModelStructure& s) {
  return s.has_dead_zones() ? static_cast<int>(s.dead_zone_thresholds.size() / 2) : 0;
}

}  // namespace

CandidateOutcome test_asymmetry(const CandidateContext& c) {
  CandidateOutcome out;
  const ResidualProfile& level = c.profile("input");
  out.statistic = level.explained;
  out.threshold = kAsymmetryThreshold;
  const auto [lo, hi] = std::minmax_element(level.means.begin(), level.means.end());
  out.evidence = "the input level explains " + percent(level.explained) +
                 " of the residual variance (level-dependent error from " + num(*lo) + " to " +
                 num(*hi) + " " + c.record.units.output +
                 ", both directions pooled): the loop is bent or asymmetric";

  const ModelStructure& base = c.base.structure;
  std::vector<std::pair<ExtensionSpec, std::string>> tries;
  const int m0 = dead_zones_per_side(base);
  for (int m = m0 + 1; m <= std::max(3, m0 + 2); ++m) {
    ExtensionSpec spec = c.base;
    spec.structure = with_dead_zones(base, c.record, m);
    tries.emplace_back(spec, family_name(spec.structure.kind) + " with " + std::to_string(m) +
                                 " dead zones per side");
  }
  if (base.kind == ModelKind::kPi || base.kind == ModelKind::kCoupledPlayPi) {
    for (const auto& scale : kCoupledScales) {
      ExtensionSpec spec = c.base;
      spec.structure.kind = ModelKind::kCoupledPlayPi;
      spec.structure.cp_scale = scale;
      tries.emplace_back(
          spec, "coupled-play PI (rb = " + num(scale[1]) + " r, rc = " + num(scale[2]) + " r)");
    }
  }
  // Dead-zone kinds regress in transformed space: compare by the simulated fit-part error.
  std::vector<ExtensionFit> fits;
  for (const auto& [spec, what] : tries) {
    fits.push_back(fit_extension(c.record, spec));
    if (!fits.back().model.hysteresis().invertibility().invertible) {
      fits.back().fit.rmse = std::numeric_limits<double>::infinity();
    }
  }
  const std::size_t kept = simplest_within(fits, kAsymmetryParsimony);
  out.fit = std::move(fits[kept]);
  out.extension = tries[kept].second;
  return out;
}

}  // namespace hystbench::compensation::details
